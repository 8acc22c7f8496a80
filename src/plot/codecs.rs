//! Bitrate against foveal quality, one line per codec family (plain, low-passed, inset): the
//! curve to the left and below wins. The target configuration's quality and the floors of
//! 4:2:0 and 4:4:4 8-bit YCbCr are drawn as horizontal lines, so "equal quality" and
//! "unreachable" can be read off.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::bench::log_flip_chart;
use super::{colour, err, legend, Plot};
use crate::bench::{CodecReport, TARGET};

pub struct CodecPlot {
    pub title: String,
    /// Per family: (kbit/s at 60 fps, foveal FLIP), by bitrate.
    pub families: Vec<(String, Vec<(f64, f64)>)>,
    /// The target configuration's foveal FLIP.
    pub target: Option<f64>,
    /// The rounded 4:2:0 conversion's foveal FLIP.
    pub floor: Option<f64>,
    /// The same with chroma at every pixel (4:4:4): about the best an 8-bit YCbCr codec shows.
    pub floor_444: Option<f64>,
}

impl CodecPlot {
    pub fn of(r: &CodecReport) -> CodecPlot {
        let mut families: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
        for row in &r.rows {
            let p = (row.kbps, row.flip_fovea);
            if !(p.0 > 0.0 && p.0.is_finite() && p.1.is_finite()) {
                continue;
            }
            match families.iter_mut().find(|(f, _)| *f == row.family) {
                Some((_, pts)) => pts.push(p),
                None => families.push((row.family.clone(), vec![p])),
            }
        }
        for (_, pts) in &mut families {
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        }
        CodecPlot {
            title: format!(
                "Bitrate vs foveal quality: {} at {}×{}, {} frames of recorded gaze{}",
                r.scene,
                r.width,
                r.height,
                r.frames,
                r.camera_note()
            ),
            families,
            target: r
                .rows
                .iter()
                .find(|x| x.name == TARGET)
                .map(|x| x.flip_fovea),
            floor: r.floors.first().map(|f| f.flip_fovea),
            floor_444: r
                .floors
                .iter()
                .find(|f| f.name.contains("4:4:4"))
                .map(|f| f.flip_fovea),
        }
    }
}

impl Plot for CodecPlot {
    fn size(&self) -> (u32, u32) {
        (1000, 640)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        root.fill(&WHITE).map_err(err)?;
        let all: Vec<(f64, f64)> = self.families.iter().flat_map(|(_, p)| p.clone()).collect();
        if all.is_empty() {
            root.draw(&Text::new("no measurements", (40, 60), ("sans-serif", 20)))
                .map_err(err)?;
            return Ok(());
        }
        let (blo, bhi) = all
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.0), b.max(p.0)));
        let fhi = all.iter().map(|p| p.1).fold(0.0, f64::max);
        let mut chart = log_flip_chart(
            root,
            &self.title,
            (blo, bhi),
            fhi,
            "kbit/s at 60 fps, keyframes included (log scale)",
            "mean FLIP within 5° of the gaze",
        )?;
        let (x0, x1) = (blo / 1.3, bhi * 1.3);
        for (level, name, c) in [
            (self.target, format!("{TARGET}'s foveal FLIP"), BLACK),
            (self.floor, "4:2:0 conversion alone".to_string(), colour(5)),
            (
                self.floor_444,
                "4:4:4 conversion alone".to_string(),
                colour(7),
            ),
        ] {
            let Some(y) = level else { continue };
            chart
                .draw_series(DashedLineSeries::new(
                    [(x0, y), (x1, y)],
                    6,
                    4,
                    c.stroke_width(1),
                ))
                .map_err(err)?
                .label(name)
                .legend(move |(x, y)| {
                    plotters::element::DashedPathElement::new(
                        vec![(x, y), (x + 20, y)],
                        5,
                        3,
                        c.stroke_width(1),
                    )
                });
        }
        for (i, (family, pts)) in self.families.iter().enumerate() {
            let c = colour(i);
            chart
                .draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))
                .map_err(err)?
                .label(family.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                });
            chart
                .draw_series(pts.iter().map(|p| Circle::new(*p, 4, c.filled())))
                .map_err(err)?;
        }
        // Lower left: cheap and sharp at once is where no codec reaches, so no point hides there.
        legend(&mut chart, SeriesLabelPosition::LowerLeft)?;
        Ok(())
    }
}
