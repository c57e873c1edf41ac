//! What the figures of `verify` and the charts of `stickslip-study` draw
//! alike: the palette, the font (shipped in verify/assets/, so plotters
//! needs no system libraries) and the axes of a panel.

use std::ops::Range;
use std::sync::Once;

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

/// Colours that survive greyscale printing in order.
pub const COLORS: [RGBColor; 6] = [
    RGBColor(0, 90, 181),
    RGBColor(220, 50, 32),
    RGBColor(0, 140, 70),
    RGBColor(150, 80, 170),
    RGBColor(230, 140, 0),
    RGBColor(60, 60, 60),
];

/// Registers verify/assets/DejaVuSans.ttf as "sans-serif" (once per
/// process; every drawing names that family).
///
/// # Errors
/// The shipped font does not parse.
pub fn register_font() -> Result<(), String> {
    static ONCE: Once = Once::new();
    let mut result = Ok(());
    ONCE.call_once(|| {
        result = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            include_bytes!("../assets/DejaVuSans.ttf"),
        )
        .map_err(|_| "verify/assets/DejaVuSans.ttf is not a usable font".to_string());
    });
    result
}

/// Sizes of a panel's text (points) and margin (pixels).
#[derive(Clone, Copy, Debug)]
pub struct AxesStyle {
    /// Title.
    pub caption: u32,
    /// Around the panel.
    pub margin: u32,
    /// Tick labels.
    pub label: u32,
    /// Axis descriptions.
    pub desc: u32,
}

/// A panel's chart: f64 against f64.
pub type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Tick label formatters for x and y.
pub type Ticks<'a> = (&'a dyn Fn(&f64) -> String, &'a dyn Fn(&f64) -> String);

/// A panel's axes on `area`: `[title, x description, y description]`, the
/// ranges, tick labels (plotters' own unless `ticks`) and no light grid
/// lines.
///
/// # Errors
/// A drawing error.
pub fn axes<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    [title, x_label, y_label]: [&str; 3],
    x: Range<f64>,
    y: Range<f64>,
    style: AxesStyle,
    ticks: Option<Ticks>,
) -> Result<Chart<'a, DB>, DrawingAreaErrorKind<DB::ErrorType>> {
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", style.caption))
        .margin(style.margin)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(x, y)?;
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(x_label).y_desc(y_label);
    if let Some((fx, fy)) = ticks {
        mesh.x_label_formatter(fx).y_label_formatter(fy);
    }
    mesh.label_style(("sans-serif", style.label))
        .axis_desc_style(("sans-serif", style.desc))
        .light_line_style(WHITE.mix(0.0))
        .draw()?;
    Ok(chart)
}
