//! Gaze prediction error against horizon, per class of eye movement: holding the last sample
//! (dashed) and the predictor (solid), median and 95th percentile in two panels.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{colour, err, legend, padded, Plot};
use crate::gaze::evaluate::HorizonError;

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
        (1100, 460)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        root.fill(&WHITE).map_err(err)?;
        let root = root
            .titled(
                &self.title,
                ("sans-serif", 18).into_font().style(FontStyle::Bold),
            )
            .map_err(err)?;
        let (left, right) = root.split_horizontally(550);
        let hmax = self.rows.iter().map(|r| r.horizon_ms).fold(1.0, f64::max);
        let panels: [(
            &DrawingArea<DB, Shift>,
            &str,
            fn(&HorizonError) -> (f64, f64),
        ); 2] = [
            (&left, "median error", |r| {
                (r.hold_median_deg, r.predicted_median_deg)
            }),
            (&right, "95th percentile error", |r| {
                (r.hold_p95_deg, r.predicted_p95_deg)
            }),
        ];
        for (area, caption, f) in panels {
            let ymax = self
                .rows
                .iter()
                .map(|r| {
                    let (a, b) = f(r);
                    a.max(b)
                })
                .filter(|v| v.is_finite())
                .fold(0.1, f64::max);
            let mut chart = ChartBuilder::on(area)
                .margin(14)
                .x_label_area_size(44)
                .y_label_area_size(60)
                .caption(caption, ("sans-serif", 15))
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
            for (i, class) in self.classes().into_iter().enumerate() {
                let c = colour(i);
                let rows: Vec<&HorizonError> =
                    self.rows.iter().filter(|r| r.class == class).collect();
                let held: Vec<(f64, f64)> = rows.iter().map(|r| (r.horizon_ms, f(r).0)).collect();
                let predicted: Vec<(f64, f64)> =
                    rows.iter().map(|r| (r.horizon_ms, f(r).1)).collect();
                chart
                    .draw_series(DashedLineSeries::new(held, 6, 4, c.stroke_width(2)))
                    .map_err(err)?
                    .label(format!("{class}: hold"))
                    .legend(move |(x, y)| {
                        plotters::element::DashedPathElement::new(
                            vec![(x, y), (x + 20, y)],
                            5,
                            3,
                            c.stroke_width(2),
                        )
                    });
                chart
                    .draw_series(LineSeries::new(predicted.clone(), c.stroke_width(2)))
                    .map_err(err)?
                    .label(format!("{class}: predicted"))
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                    });
                chart
                    .draw_series(predicted.into_iter().map(|p| Circle::new(p, 3, c.filled())))
                    .map_err(err)?;
            }
            legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
        }
        Ok(())
    }
}
