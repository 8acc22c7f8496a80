//! Gaze prediction error against horizon: one panel per class of eye movement, each method
//! (hold, constant velocity, predictor) a colour, the median solid and the 95th percentile
//! dashed.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{colour, err, legend, padded, Plot};
use crate::gaze::evaluate::{HorizonError, METHODS};

pub struct GazePlot {
    pub title: String,
    pub rows: Vec<HorizonError>,
}

impl GazePlot {
    fn classes(&self) -> Vec<&'static str> {
        let mut c: Vec<&'static str> = self.rows.iter().map(|r| r.class).collect();
        c.sort_unstable();
        c.dedup();
        c
    }
}

impl Plot for GazePlot {
    fn size(&self) -> (u32, u32) {
        (1100, 840)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        root.fill(&WHITE).map_err(err)?;
        let root = root
            .titled(
                &self.title,
                ("sans-serif", 18).into_font().style(FontStyle::Bold),
            )
            .map_err(err)?;
        let hmax = self.rows.iter().map(|r| r.horizon_ms).fold(1.0, f64::max);
        let classes = self.classes();
        let areas = root.split_evenly((classes.len().div_ceil(2).max(1), 2));
        for (area, class) in areas.iter().zip(classes) {
            let rows: Vec<&HorizonError> = self.rows.iter().filter(|r| r.class == class).collect();
            let ymax = rows
                .iter()
                .flat_map(|r| r.methods.iter().map(|m| m.p95))
                .filter(|v| v.is_finite())
                .fold(0.1, f64::max);
            let n = rows.iter().map(|r| r.samples).max().unwrap_or(0);
            let mut chart = ChartBuilder::on(area)
                .margin(14)
                .x_label_area_size(44)
                .y_label_area_size(60)
                .caption(format!("{class} (up to {n} samples)"), ("sans-serif", 15))
                .build_cartesian_2d(0.0..hmax * 1.08, padded(0.0, ymax, false))
                .map_err(err)?;
            chart
                .configure_mesh()
                .light_line_style(WHITE.mix(0.0))
                .x_desc("prediction horizon, ms")
                .y_desc("angular error, degrees")
                .axis_desc_style(("sans-serif", 14))
                .label_style(("sans-serif", 12))
                .draw()
                .map_err(err)?;
            for (m, method) in METHODS.iter().enumerate() {
                let c = colour(m);
                let median: Vec<(f64, f64)> = rows
                    .iter()
                    .map(|r| (r.horizon_ms, r.methods[m].median))
                    .collect();
                let p95: Vec<(f64, f64)> = rows
                    .iter()
                    .map(|r| (r.horizon_ms, r.methods[m].p95))
                    .collect();
                chart
                    .draw_series(LineSeries::new(median.clone(), c.stroke_width(2)))
                    .map_err(err)?
                    .label(format!("{method}: median"))
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                    });
                chart
                    .draw_series(median.into_iter().map(|p| Circle::new(p, 3, c.filled())))
                    .map_err(err)?;
                chart
                    .draw_series(DashedLineSeries::new(p95, 6, 4, c.stroke_width(2)))
                    .map_err(err)?
                    .label(format!("{method}: p95"))
                    .legend(move |(x, y)| {
                        plotters::element::DashedPathElement::new(
                            vec![(x, y), (x + 20, y)],
                            5,
                            3,
                            c.stroke_width(2),
                        )
                    });
            }
            legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
        }
        Ok(())
    }
}
