//! Plots people can read, drawn with `plotters` to SVG and PNG from the same code: the bench's
//! cost-vs-error chart ([`bench`]), the codecs' bytes against quality ([`codecs`]), the load sweep ([`load`]) and gaze prediction error
//! against horizon ([`gaze`]). Labels use DejaVu Sans, embedded, so a PNG looks the same on
//! every machine.

pub mod bench;
pub mod codecs;
pub mod gaze;
pub mod load;

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;

#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    #[error("drawing {path}: {message}")]
    Draw { path: PathBuf, message: String },
    #[error("the embedded font does not load")]
    Font,
}

/// Registers the embedded font once; every plot asks for "sans-serif".
fn font() -> Result<(), PlotError> {
    static DONE: OnceLock<bool> = OnceLock::new();
    let ok = *DONE.get_or_init(|| {
        let bytes = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
        plotters::style::register_font("sans-serif", FontStyle::Normal, bytes).is_ok()
            && plotters::style::register_font("sans-serif", FontStyle::Bold, bytes).is_ok()
    });
    ok.then_some(()).ok_or(PlotError::Font)
}

/// A plot drawn on any backend: the same function makes the SVG and the PNG.
pub trait Plot {
    fn size(&self) -> (u32, u32);
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String>;
}

/// Writes `base.svg` and `base.png`.
pub fn write(plot: &impl Plot, base: &Path) -> Result<(), PlotError> {
    font()?;
    let size = plot.size();
    let svg = base.with_extension("svg");
    let png = base.with_extension("png");
    let fail = |path: &Path, message: String| PlotError::Draw {
        path: path.to_path_buf(),
        message,
    };
    {
        let root = SVGBackend::new(&svg, size).into_drawing_area();
        plot.draw(&root).map_err(|e| fail(&svg, e))?;
        root.present().map_err(|e| fail(&svg, e.to_string()))?;
    }
    let root = BitMapBackend::new(&png, size).into_drawing_area();
    plot.draw(&root).map_err(|e| fail(&png, e))?;
    root.present().map_err(|e| fail(&png, e.to_string()))?;
    Ok(())
}

/// Plotters' errors carry the backend's error type; plots report them as text.
fn err<E: std::fmt::Debug>(e: E) -> String {
    format!("{e:?}")
}

/// Ten distinct colours (the codec chart draws eight families; six repeated two of them).
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(127, 127, 127),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

fn colour(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// The legend every plot draws: inside the plot, on a white panel with a thin border.
fn legend<'a, DB, CT>(
    chart: &mut ChartContext<'a, DB, CT>,
    at: SeriesLabelPosition,
) -> Result<(), String>
where
    DB: DrawingBackend + 'a,
    CT: plotters::coord::CoordTranslate,
{
    chart
        .configure_series_labels()
        .position(at)
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK.mix(0.4))
        .label_font(("sans-serif", 12))
        .draw()
        .map_err(err)
}

/// A linear axis's tick as text, with as few decimals as it needs (up to two): "3", "2.5",
/// "0.25". One precision for the whole axis printed "2 2 2 3" on a span of a few units, or
/// "1.0 2.0" where whole numbers were the ticks.
fn linear_tick(v: f64) -> String {
    (0..2)
        .map(|d| format!("{v:.d$}"))
        .find(|s| {
            s.parse::<f64>()
                .is_ok_and(|p| (p - v).abs() <= 1e-9 * v.abs().max(1.0))
        })
        .unwrap_or_else(|| format!("{v:.2}"))
}

/// A range with a little room on both sides (and never empty).
fn padded(lo: f64, hi: f64, log: bool) -> std::ops::Range<f64> {
    if log {
        let (lo, hi) = (lo.max(1e-6), hi.max(lo.max(1e-6) * 1.01));
        (lo / 1.3)..(hi * 1.3)
    } else {
        let span = (hi - lo).max(hi.abs() * 0.1).max(1e-6);
        (lo - 0.08 * span).min(if lo >= 0.0 { 0.0 } else { lo })..(hi + 0.12 * span)
    }
}
