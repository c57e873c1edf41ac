//! Scatter and line charts as PNG and SVG (plotters without system
//! libraries; palette, font and axes from `stickslip_verify::plotting`).

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;
use stickslip_verify::plotting::{axes, register_font, AxesStyle};

/// Colours that survive greyscale printing in order.
pub use stickslip_verify::plotting::COLORS;

/// Text sizes and margin of the study charts.
const STYLE: AxesStyle = AxesStyle {
    caption: 18,
    margin: 10,
    label: 13,
    desc: 15,
};

/// Marker shape of a series.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Marker {
    /// No marker (line only).
    None,
    /// Circle.
    Circle,
    /// Square.
    Square,
    /// Triangle.
    Triangle,
    /// Diagonal cross.
    Cross,
}

/// One data series.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend label (empty: not in the legend).
    pub label: String,
    /// Colour.
    pub color: RGBColor,
    /// Marker shape.
    pub marker: Marker,
    /// Filled marker (else hollow).
    pub filled: bool,
    /// Join the points with a line.
    pub line: bool,
    /// (x, y) data.
    pub points: Vec<(f64, f64)>,
}

/// One chart.
#[derive(Clone, Debug)]
pub struct Panel {
    /// Title.
    pub title: String,
    /// x-axis label.
    pub x_label: String,
    /// y-axis label.
    pub y_label: String,
    /// Logarithmic x axis.
    pub x_log: bool,
    /// Logarithmic y axis.
    pub y_log: bool,
    /// Series.
    pub series: Vec<Series>,
    /// Vertical reference lines at these x.
    pub vlines: Vec<f64>,
    /// Draw the legend inside the panel (else only the figure's legend
    /// strip, see [`save`]).
    pub legend: bool,
}

fn axis(v: f64, log: bool) -> Option<f64> {
    if !v.is_finite() {
        return None;
    }
    if log {
        (v > 0.0).then(|| v.log10())
    } else {
        Some(v)
    }
}

fn tick(v: f64, log: bool) -> String {
    if log {
        let x = 10f64.powf(v);
        if (v - v.round()).abs() < 1e-9 {
            format!("1e{}", v.round() as i64)
        } else {
            format!("{x:.1e}")
        }
    } else {
        let a = v.abs();
        if a != 0.0 && !(1e-2..1e4).contains(&a) {
            format!("{v:.1e}")
        } else {
            format!("{v:.3}")
                .trim_end_matches('0')
                .trim_end_matches('.')
                .to_string()
        }
    }
}

fn draw_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &Panel) -> Result<(), String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| format!("{}: {e}", p.title);
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    let mapped: Vec<Vec<(f64, f64)>> = p
        .series
        .iter()
        .map(|s| {
            s.points
                .iter()
                .filter_map(|&(x, y)| Some((axis(x, p.x_log)?, axis(y, p.y_log)?)))
                .collect()
        })
        .collect();
    for pts in &mapped {
        for &(x, y) in pts {
            x0 = x0.min(x);
            x1 = x1.max(x);
            y0 = y0.min(y);
            y1 = y1.max(y);
        }
    }
    for &v in &p.vlines {
        if let Some(x) = axis(v, p.x_log) {
            x0 = x0.min(x);
            x1 = x1.max(x);
        }
    }
    if !x0.is_finite() {
        (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
    }
    let px = 0.05 * (x1 - x0).max(1e-9);
    let py = 0.05 * (y1 - y0).max(1e-9);
    let (x0, x1, y0, y1) = (x0 - px, x1 + px, y0 - py, y1 + py);
    let (xl, yl) = (p.x_log, p.y_log);
    let mut chart = axes(
        area,
        [&p.title, &p.x_label, &p.y_label],
        x0..x1,
        y0..y1,
        STYLE,
        Some((&|v| tick(*v, xl), &|v| tick(*v, yl))),
    )
    .map_err(err)?;
    for &v in &p.vlines {
        if let Some(x) = axis(v, p.x_log) {
            chart
                .draw_series(LineSeries::new(
                    [(x, y0), (x, y1)],
                    BLACK.mix(0.5).stroke_width(1),
                ))
                .map_err(err)?;
        }
    }
    for (s, pts) in p.series.iter().zip(&mapped) {
        let color = s.color;
        let style = if s.filled {
            color.filled()
        } else {
            color.stroke_width(2)
        };
        if s.line {
            let a = chart
                .draw_series(LineSeries::new(pts.iter().copied(), color.stroke_width(2)))
                .map_err(err)?;
            if s.marker == Marker::None && !s.label.is_empty() {
                a.label(s.label.as_str()).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                });
            }
        }
        if s.marker == Marker::None {
            continue;
        }
        let label = s.label.clone();
        let z = 5;
        macro_rules! markers {
            ($make:expr) => {{
                let a = chart
                    .draw_series(pts.iter().map(|&c| EmptyElement::at(c) + $make))
                    .map_err(err)?;
                if !label.is_empty() {
                    a.label(label.as_str())
                        .legend(move |(x, y)| EmptyElement::at((x + 8, y)) + $make);
                }
            }};
        }
        match s.marker {
            Marker::None => {}
            Marker::Circle => markers!(Circle::new((0, 0), z, style)),
            Marker::Square => markers!(Rectangle::new([(-z, -z), (z, z)], style)),
            Marker::Triangle if s.filled => markers!(Polygon::new(
                vec![(0, -z - 1), (z + 1, z), (-z - 1, z)],
                style
            )),
            Marker::Triangle => markers!(PathElement::new(
                vec![(0, -z - 1), (z + 1, z), (-z - 1, z), (0, -z - 1)],
                style
            )),
            Marker::Cross => markers!(PathElement::new(
                vec![(-z, -z), (z, z), (0, 0), (z, -z), (-z, z)],
                color.stroke_width(2)
            )),
        }
    }
    if !p.legend {
        return Ok(());
    }
    chart
        .configure_series_labels()
        .label_font(("sans-serif", 12))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(err)?;
    Ok(())
}

/// Draws `panels` in a grid of `cols` columns to `stem`.png and `stem`.svg,
/// each panel `w` × `h` pixels, under a strip holding the labels and
/// markers of `legend` (empty: no strip); returns the two paths.
///
/// # Errors
/// An unwritable file or a drawing error (names the chart).
pub fn save(
    stem: &Path,
    panels: &[Panel],
    legend: &[Series],
    cols: usize,
    w: u32,
    h: u32,
) -> Result<Vec<PathBuf>, String> {
    register_font()?;
    let cols = cols.max(1);
    let rows = panels.len().div_ceil(cols).max(1);
    let per_line = ((w * cols as u32) / 300).max(1) as usize;
    let strip = if legend.is_empty() {
        0
    } else {
        22 * legend.len().div_ceil(per_line) as u32 + 16
    };
    let size = (w * cols as u32, h * rows as u32 + strip);
    let png = stem.with_extension("png");
    let svg = stem.with_extension("svg");
    let fig = Fig {
        panels,
        legend,
        rows,
        cols,
        strip,
        per_line,
    };
    draw_all(BitMapBackend::new(&png, size).into_drawing_area(), &fig)
        .map_err(|e| format!("{}: {e}", png.display()))?;
    draw_all(SVGBackend::new(&svg, size).into_drawing_area(), &fig)
        .map_err(|e| format!("{}: {e}", svg.display()))?;
    Ok(vec![png, svg])
}

struct Fig<'a> {
    panels: &'a [Panel],
    legend: &'a [Series],
    rows: usize,
    cols: usize,
    strip: u32,
    per_line: usize,
}

fn draw_all<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, fig: &Fig) -> Result<(), String> {
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let (top, body) = root.split_vertically(fig.strip);
    let col_w = top.dim_in_pixel().0 as i32 / fig.per_line as i32;
    for (k, s) in fig.legend.iter().enumerate() {
        let x = 20 + col_w * (k % fig.per_line) as i32;
        let y = 14 + 22 * (k / fig.per_line) as i32;
        let style = if s.filled {
            s.color.filled()
        } else {
            s.color.stroke_width(2)
        };
        let z = 5;
        let e = |r: Result<(), DrawingAreaErrorKind<DB::ErrorType>>| r.map_err(|e| e.to_string());
        match s.marker {
            Marker::None => e(top.draw(&PathElement::new(
                vec![(x - 8, y), (x + 12, y)],
                s.color.stroke_width(2),
            )))?,
            Marker::Circle => e(top.draw(&Circle::new((x, y), z, style)))?,
            Marker::Square => {
                e(top.draw(&Rectangle::new([(x - z, y - z), (x + z, y + z)], style)))?
            }
            Marker::Triangle if s.filled => e(top.draw(&Polygon::new(
                vec![(x, y - z - 1), (x + z + 1, y + z), (x - z - 1, y + z)],
                style,
            )))?,
            Marker::Triangle => e(top.draw(&PathElement::new(
                vec![
                    (x, y - z - 1),
                    (x + z + 1, y + z),
                    (x - z - 1, y + z),
                    (x, y - z - 1),
                ],
                style,
            )))?,
            Marker::Cross => e(top.draw(&PathElement::new(
                vec![
                    (x - z, y - z),
                    (x + z, y + z),
                    (x, y),
                    (x + z, y - z),
                    (x - z, y + z),
                ],
                s.color.stroke_width(2),
            )))?,
        }
        e(top.draw(&Text::new(
            s.label.clone(),
            (x + 18, y - 8),
            ("sans-serif", 14).into_font(),
        )))?;
    }
    let areas = body.split_evenly((fig.rows, fig.cols));
    for (area, p) in areas.iter().zip(fig.panels) {
        draw_panel(area, p)?;
    }
    root.present().map_err(|e| e.to_string())?;
    Ok(())
}
