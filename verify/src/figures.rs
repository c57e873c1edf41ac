//! The paper's Figs. 3-18 redrawn from our runs of cases/martins-oden/, and
//! an energy-ledger figure, as PNG and SVG (plotters, no system libraries:
//! the font ships in verify/assets/).

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::plotting::{axes, register_font, AxesStyle, COLORS};
use crate::scene::Trace;
use crate::{run_cases, PaperCase, Run};

/// The colour index of a curve drawn thick and black, apart from the
/// palette: a reference the others are compared with.
const REFERENCE: usize = usize::MAX;

/// One curve: legend label, points, colour index (or [`REFERENCE`]).
#[derive(Debug)]
struct Series {
    label: String,
    points: Vec<(f64, f64)>,
    color: usize,
}

/// One chart.
#[derive(Debug)]
struct Panel {
    title: String,
    x_label: String,
    y_label: String,
    /// The paper's axis range, widened to the data if it leaves it.
    y_range: Option<(f64, f64)>,
    series: Vec<Series>,
    /// Where the legend sits (away from the curves).
    legend: SeriesLabelPosition,
}

/// A figure: panels stacked vertically.
#[derive(Debug)]
struct Figure {
    stem: String,
    panels: Vec<Panel>,
}

/// Text sizes and margin of the paper's figures.
const STYLE: AxesStyle = AxesStyle {
    caption: 20,
    margin: 12,
    label: 15,
    desc: 17,
};

fn draw<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, fig: &Figure) -> Result<(), String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| format!("{}: {e}", fig.stem);
    root.fill(&WHITE).map_err(err)?;
    let areas = root.split_evenly((fig.panels.len(), 1));
    for (area, p) in areas.iter().zip(&fig.panels) {
        let (mut x0, mut x1, mut y0, mut y1) = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        for s in &p.series {
            for &(x, y) in &s.points {
                x0 = x0.min(x);
                x1 = x1.max(x);
                y0 = y0.min(y);
                y1 = y1.max(y);
            }
        }
        if let Some((a, b)) = p.y_range {
            y0 = y0.min(a);
            y1 = y1.max(b);
        } else {
            let pad = 0.05 * (y1 - y0).max(1e-12);
            y0 -= pad;
            y1 += pad;
        }
        let mut chart = axes(
            area,
            [&p.title, &p.x_label, &p.y_label],
            x0..x1,
            y0..y1,
            STYLE,
            None,
        )
        .map_err(err)?;
        for s in &p.series {
            let (color, width) = if s.color == REFERENCE {
                (BLACK, 3)
            } else {
                (COLORS[s.color % COLORS.len()], 2)
            };
            chart
                .draw_series(LineSeries::new(
                    s.points.iter().copied(),
                    color.stroke_width(width),
                ))
                .map_err(err)?
                .label(s.label.as_str())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 22, y)], color.stroke_width(width))
                });
        }
        chart
            .configure_series_labels()
            .label_font(("sans-serif", 15))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(p.legend.clone())
            .draw()
            .map_err(err)?;
    }
    root.present().map_err(err)?;
    Ok(())
}

fn series(label: &str, t: &[f64], y: &[f64], color: usize) -> Series {
    Series {
        label: label.to_string(),
        points: t.iter().copied().zip(y.iter().copied()).collect(),
        color,
    }
}

/// σ_T at nodes 71 and 81 (the paper's friction-stress figures).
fn friction_series(t: &Trace) -> Vec<Series> {
    vec![
        series("node 71 (7, 0)", &t.t, &t.sigma71, 0),
        series("node 81 (8, 0)", &t.t, &t.sigma81, 1),
    ]
}

fn trace<'a>(runs: &'a [Run], name: &str) -> Result<&'a Trace, String> {
    let run = runs
        .iter()
        .find(|r| r.case.name == name)
        .ok_or_else(|| format!("cases/martins-oden/{name}.toml is missing"))?;
    match &run.trace.error {
        Some(e) => Err(format!("{name}: {e}")),
        None => Ok(&run.trace),
    }
}

fn panel(title: &str, y_label: &str, y_range: Option<(f64, f64)>, series: Vec<Series>) -> Panel {
    Panel {
        title: title.to_string(),
        x_label: "time t".to_string(),
        y_label: y_label.to_string(),
        y_range,
        series,
        legend: SeriesLabelPosition::UpperRight,
    }
}

fn at(mut p: Panel, legend: SeriesLabelPosition) -> Panel {
    p.legend = legend;
    p
}

/// σ_T along Γ_C at the sample nearest each of `times`.
fn distribution(t: &Trace, times: &[f64]) -> Vec<Series> {
    times
        .iter()
        .enumerate()
        .map(|(c, &want)| {
            let k = (0..t.t.len())
                .min_by(|&a, &b| (t.t[a] - want).abs().total_cmp(&(t.t[b] - want).abs()))
                .unwrap_or(0);
            let mut pts: Vec<(f64, f64)> = t
                .contact_x
                .iter()
                .copied()
                .zip(t.sigma_all[k].iter().copied())
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            Series {
                label: format!("t = {:.3}", t.t[k]),
                points: pts,
                color: c,
            }
        })
        .collect()
}

fn energy(t: &Trace, f: fn(&stickslip_time::Energy) -> f64) -> Vec<f64> {
    t.energy.iter().map(f).collect()
}

/// The static curve of Fig. 5: σ_T along Γ_C at the end of the
/// quasi-static run (the full load).
fn static_distribution(t: &Trace, label: &str, color: usize) -> Series {
    let last = t.sigma_all.last().cloned().unwrap_or_default();
    let mut points: Vec<(f64, f64)> = t.contact_x.iter().copied().zip(last).collect();
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    Series {
        label: label.to_string(),
        points,
        color,
    }
}

/// Reads and runs the static case of Fig. 5 (`STATIC_CASE`).
fn static_run(root: &Path) -> Result<Trace, String> {
    let case = PaperCase::read(&root.join(STATIC_CASE))?;
    let trace = crate::scene::run(&case.scene()?);
    match trace.error {
        Some(e) => Err(format!("{STATIC_CASE}: {e}")),
        None => Ok(trace),
    }
}

/// The paper's Fig. 5 static analysis: the slab under t_x = 300 (twice the
/// dynamic runs' end load), by quasi-static increments.
pub const STATIC_CASE: &str = "cases/quasi-static/slab-static-tx300.toml";

fn figures(runs: &[Run], static_trace: &Trace) -> Result<Vec<Figure>, String> {
    let eps_cases = [
        ("cd-step-eps1", "ε = 1"),
        ("cd-step-eps1e-2", "ε = 1e-2"),
        ("cd-step-eps1e-4", "ε = 1e-4"),
    ];
    let mut figs = Vec::new();

    // Figs. 3, 6: horizontal displacement of nodes 81 and 85 (H(t), CD).
    let mut s = Vec::new();
    for (i, (name, label)) in eps_cases.iter().enumerate() {
        let t = trace(runs, name)?;
        s.push(series(&format!("node 81, {label}"), &t.t, &t.ux81, i));
        s.push(series(&format!("node 85, {label}"), &t.t, &t.ux85, i + 3));
    }
    figs.push(Figure {
        stem: "fig03-06-displacement-cd".into(),
        panels: vec![at(
            panel(
                "Horizontal displacement, central difference, Δt = 1e-3, θ = H(t) (cf. Figs. 3, 6)",
                "u_x",
                Some((0.5, 1.0)),
                s,
            ),
            SeriesLabelPosition::LowerLeft,
        )],
    });

    // Figs. 4, 8: friction stress at nodes 71 and 81, one panel per ε.
    let mut panels = Vec::new();
    for (name, label) in eps_cases {
        let t = trace(runs, name)?;
        panels.push(panel(
            &format!("Friction stress, central difference, {label} (cf. Figs. 4, 8)"),
            "σ_T",
            Some((-20.0, 100.0)),
            friction_series(t),
        ));
    }
    figs.push(Figure {
        stem: "fig04-08-friction-cd".into(),
        panels,
    });

    // Fig. 7: tangential velocity of node 81.
    let mut s = Vec::new();
    for (i, (name, label)) in eps_cases.iter().enumerate() {
        let t = trace(runs, name)?;
        s.push(series(&format!("node 81, {label}"), &t.t, &t.v81, i));
    }
    figs.push(Figure {
        stem: "fig07-velocity-cd".into(),
        panels: vec![panel(
            "Tangential velocity of node 81, central difference (cf. Fig. 7)",
            "v_T",
            Some((-5.0, 0.0)),
            s,
        )],
    });

    // Friction-stress distribution along Γ_C at several times.
    let t = trace(runs, "cd-step-eps1e-4")?;
    let times = [0.005, 0.02, 0.05, 0.1, 0.2, 0.5];
    let mut curves = distribution(t, &times);
    // Fig. 5 also plots the static analysis under t_x = 300.
    curves.push(static_distribution(
        static_trace,
        "static, |t_x| = 300 (quasi-static, ε = 1e-4)",
        REFERENCE,
    ));
    let mut p1 = panel(
        "Friction stress along Γ_C, central difference, ε = 1e-4, θ = H(t), and static (cf. Fig. 5)",
        "σ_T",
        Some((-20.0, 100.0)),
        curves,
    );
    p1.x_label = "x along Γ_C".into();
    p1.legend = SeriesLabelPosition::UpperLeft;
    let ts = trace(runs, "cd-sin-eps1e-4")?;
    let mut p2 = panel(
        "Friction stress along Γ_C, central difference, ε = 1e-4, θ = sin 8πt",
        "σ_T",
        Some((-100.0, 100.0)),
        distribution(ts, &[0.05, 0.1, 0.15, 0.2, 0.3, 0.4]),
    );
    p2.x_label = "x along Γ_C".into();
    p2.legend = SeriesLabelPosition::UpperLeft;
    figs.push(Figure {
        stem: "friction-distribution".into(),
        panels: vec![p1, p2],
    });

    // Fig. 9: total mechanical energy.
    let mut s = Vec::new();
    for (i, (name, label)) in eps_cases.iter().enumerate() {
        let t = trace(runs, name)?;
        s.push(series(
            &format!("central difference, {label}"),
            &t.t,
            &energy(t, |e| e.total),
            i,
        ));
    }
    for (i, (name, label)) in [
        ("newmark-step-reduced", "Newmark ¼,½ reduced"),
        ("newmark-damped-step", "Newmark 0.3025, 0.6"),
    ]
    .iter()
    .enumerate()
    {
        let t = trace(runs, name)?;
        s.push(series(
            &format!("{label}, ε = 1e-4"),
            &t.t,
            &energy(t, |e| e.total),
            i + 3,
        ));
    }
    figs.push(Figure {
        stem: "fig09-energy".into(),
        panels: vec![panel(
            "Total mechanical energy, θ = H(t) (cf. Fig. 9)",
            "E",
            Some((-200.0, -185.0)),
            s,
        )],
    });

    // Figs. 10, 13: displacement, Newmark.
    let nm = [
        ("newmark-step", "Newmark ¼,½, Δt = 5e-3"),
        (
            "newmark-step-reduced",
            "Newmark ¼,½, reduced to 1e-7 after sticking",
        ),
        ("newmark-damped-step", "Newmark 0.3025, 0.6, Δt = 5e-3"),
    ];
    let mut s = Vec::new();
    for (i, (name, label)) in nm.iter().enumerate() {
        let t = trace(runs, name)?;
        s.push(series(&format!("node 81, {label}"), &t.t, &t.ux81, i));
        s.push(series(&format!("node 85, {label}"), &t.t, &t.ux85, i + 3));
    }
    figs.push(Figure {
        stem: "fig10-13-displacement-newmark".into(),
        panels: vec![at(
            panel(
                "Horizontal displacement, Newmark, ε = 1e-4 (cf. Figs. 10, 13)",
                "u_x",
                Some((0.5, 1.0)),
                s,
            ),
            SeriesLabelPosition::LowerLeft,
        )],
    });

    // Figs. 11, 12, 14, 15: friction stress, Newmark.
    let figs_nm = ["Fig. 11", "Fig. 12", "Figs. 14-15"];
    let mut panels = Vec::new();
    for ((name, label), which) in nm.iter().zip(figs_nm) {
        let t = trace(runs, name)?;
        panels.push(panel(
            &format!("Friction stress, {label} (cf. {which})"),
            "σ_T",
            Some((-20.0, 100.0)),
            friction_series(t),
        ));
    }
    figs.push(Figure {
        stem: "fig11-15-friction-newmark".into(),
        panels,
    });

    // Figs. 16-18: θ = sin 8πt.
    let t = trace(runs, "cd-sin-eps1e-4")?;
    figs.push(Figure {
        stem: "fig16-18-sin".into(),
        panels: vec![
            panel(
                "Horizontal displacement, central difference, ε = 1e-4, θ = sin 8πt (cf. Fig. 16)",
                "u_x",
                Some((0.5, 1.5)),
                vec![
                    series("node 81 (8, 0)", &t.t, &t.ux81, 0),
                    series("node 85 (8, 1)", &t.t, &t.ux85, 1),
                ],
            ),
            panel(
                "Friction stress, θ = sin 8πt (cf. Figs. 17-18)",
                "σ_T",
                Some((-100.0, 100.0)),
                friction_series(t),
            ),
        ],
    });

    // The energy ledger (METHOD.md §6).
    let mut panels = Vec::new();
    for (name, label) in [
        ("cd-step-eps1e-4", "central difference, ε = 1e-4, θ = H(t)"),
        (
            "newmark-step-reduced",
            "Newmark ¼,½ with step reduction, ε = 1e-4",
        ),
    ] {
        let t = trace(runs, name)?;
        let e0 = t.energy[0].kinetic + t.energy[0].strain;
        panels.push(panel(
            &format!("Energy ledger, {label}"),
            "energy",
            None,
            vec![
                series("kinetic ½vᵀMv", &t.t, &energy(t, |e| e.kinetic), 0),
                series(
                    "strain ½rᵀKr − initial",
                    &t.t,
                    &energy(t, |e| e.strain)
                        .iter()
                        .map(|s| s - e0)
                        .collect::<Vec<_>>(),
                    1,
                ),
                series("external work", &t.t, &energy(t, |e| e.external_work), 2),
                series(
                    "friction dissipation",
                    &t.t,
                    &energy(t, |e| e.dissipated),
                    3,
                ),
                series("balance residual", &t.t, &energy(t, |e| e.balance), 5),
            ],
        ));
    }
    figs.push(Figure {
        stem: "energy-ledger".into(),
        panels,
    });
    Ok(figs)
}

/// Runs the paper's cases and writes every figure to `out` as PNG and SVG.
///
/// # Errors
/// Unreadable cases, a failed run, an unwritable directory, or a drawing
/// error, each naming the file.
pub fn draw_all(root: &Path, out: &Path) -> Result<Vec<PathBuf>, String> {
    register_font()?;
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let runs = run_cases(root, None, &[])?;
    let static_trace = static_run(root)?;
    let mut written = Vec::new();
    for fig in figures(&runs, &static_trace)? {
        let height = 360 * fig.panels.len() as u32 + 40;
        let png = out.join(format!("{}.png", fig.stem));
        draw(
            BitMapBackend::new(&png, (1000, height)).into_drawing_area(),
            &fig,
        )?;
        written.push(png);
        let svg = out.join(format!("{}.svg", fig.stem));
        draw(
            SVGBackend::new(&svg, (1000, height)).into_drawing_area(),
            &fig,
        )?;
        written.push(svg);
    }
    Ok(written)
}
