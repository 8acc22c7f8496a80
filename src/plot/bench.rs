//! The bench's cost-vs-error chart: one point per configuration (medians over the run's
//! groups) on a log time axis, the Pareto front drawn and its points labelled, presets in
//! bold, the legend inside the plot.

use crate::stats::median;
use std::collections::BTreeMap;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{colour, err, legend, padded, Plot};
use crate::bench::{pareto_front, BenchReport};

/// A chart with a log x axis over `x` (ticks at 1, 2, 5 × 10ⁿ) and FLIP from 0 up to `flip_max`
/// on y: the bench's cost-vs-error chart and the codecs' bitrate-vs-quality chart.
pub(super) type LogFlipChart<'a, DB> = ChartContext<
    'a,
    DB,
    Cartesian2d<
        plotters::coord::combinators::WithKeyPoints<plotters::coord::combinators::LogCoord<f64>>,
        plotters::coord::types::RangedCoordf64,
    >,
>;

pub(super) fn log_flip_chart<'a, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    title: &str,
    x: (f64, f64),
    flip_max: f64,
    x_desc: &str,
    y_desc: &str,
) -> Result<LogFlipChart<'a, DB>, String> {
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 18).into_font().style(FontStyle::Bold))
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(70)
        .build_cartesian_2d(
            padded(x.0, x.1, true)
                .log_scale()
                .with_key_points(one_two_five(x.0, x.1)),
            padded(0.0, flip_max, false),
        )
        .map_err(err)?;
    chart
        .configure_mesh()
        .light_line_style(WHITE.mix(0.0))
        .x_desc(x_desc)
        .y_desc(y_desc)
        .axis_desc_style(("sans-serif", 15))
        .label_style(("sans-serif", 13))
        .x_label_formatter(&|v| tick_label(*v))
        .y_label_formatter(&|v| format!("{v:.3}"))
        .draw()
        .map_err(err)?;
    Ok(chart)
}

/// A log axis's 1-2-5 key point as text: whole numbers from 1 up, else to three decimals (a
/// GPU's frames take fractions of a millisecond, which `{:.0}` printed as "0").
fn tick_label(v: f64) -> String {
    if v >= 1.0 {
        format!("{v:.0}")
    } else {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').to_string()
    }
}

/// One configuration's medians.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    pub name: String,
    pub frame_ms: f64,
    pub flip: f64,
    pub preset: bool,
    pub pareto: bool,
    /// Where a foveated configuration would sit if its frame cost `full`'s times the share of
    /// pixels it shades: the distance to the limit, drawn as a hollow marker joined to the point.
    pub ideal_ms: Option<f64>,
    /// Where it would sit with foveation's own passes free and only shading falling with the
    /// samples (`bench::bound_vs_full`), on the same line.
    pub bound_ms: Option<f64>,
}

pub struct BenchPlot {
    pub title: String,
    pub points: Vec<Point>,
}

/// Tick values 1, 2, 5 × 10ⁿ around [lo, hi]: readable labels on a log axis.
fn one_two_five(lo: f64, hi: f64) -> Vec<f64> {
    let mut out = Vec::new();
    let mut decade = 10f64.powf((lo / 1.3).max(1e-6).log10().floor());
    while decade <= hi * 1.3 {
        for m in [1.0, 2.0, 5.0] {
            let v = m * decade;
            if v >= lo / 1.3 && v <= hi * 1.3 {
                out.push(v);
            }
        }
        decade *= 10.0;
    }
    out
}

impl BenchPlot {
    pub fn of(report: &BenchReport) -> BenchPlot {
        // Per configuration: frame times, FLIPs, ideal and bound frame times over the groups.
        type Series = (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>);
        let mut by_config: BTreeMap<&str, Series> = BTreeMap::new();
        let mut order = Vec::new();
        for r in &report.records {
            let e = by_config.entry(&r.config).or_insert_with(|| {
                order.push(r.config.as_str());
                (Vec::new(), Vec::new(), Vec::new(), Vec::new())
            });
            e.0.push(r.frame_ms.median);
            e.1.push(r.errors.flip);
            if let (Some(a), Some(i)) = (r.speedup_vs_full, r.ideal_vs_full) {
                e.2.push(r.frame_ms.median * a / i);
            }
            if let (Some(a), Some(b)) = (r.speedup_vs_full, r.bound_vs_full) {
                e.3.push(r.frame_ms.median * a / b);
            }
        }
        let mut points: Vec<Point> = order
            .iter()
            .filter_map(|name| {
                let (t, f, ideal, bound) = by_config.get(name)?;
                Some(Point {
                    name: name.to_string(),
                    frame_ms: median(t.clone()),
                    flip: median(f.clone()),
                    preset: crate::settings::Preset::from_name(name).is_some(),
                    pareto: false,
                    ideal_ms: (!ideal.is_empty()).then(|| median(ideal.clone())),
                    bound_ms: (!bound.is_empty()).then(|| median(bound.clone())),
                })
            })
            .filter(|p| p.frame_ms.is_finite() && p.flip.is_finite() && p.frame_ms > 0.0)
            .collect();
        let coords: Vec<(f64, f64)> = points.iter().map(|p| (p.frame_ms, p.flip)).collect();
        for i in pareto_front(&coords) {
            points[i].pareto = true;
        }
        BenchPlot {
            title: format!(
                "Cost vs error against the reference, {}",
                report.machine.adapter.split(" (").next().unwrap_or("?")
            ),
            points,
        }
    }
}

impl BenchPlot {
    /// The points with a positive frame time `at` (ideal, bound) to draw beside them.
    fn beside(&self, at: impl Fn(&Point) -> Option<f64>) -> Vec<(&Point, f64)> {
        self.points
            .iter()
            .filter_map(|p| Some((p, at(p).filter(|v| *v > 0.0)?)))
            .collect()
    }
}

impl Plot for BenchPlot {
    fn size(&self) -> (u32, u32) {
        (1000, 640)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        root.fill(&WHITE).map_err(err)?;
        let title = if self.title.chars().count() > 90 {
            format!("{}…", self.title.chars().take(89).collect::<String>())
        } else {
            self.title.clone()
        };
        if self.points.is_empty() {
            root.draw(&Text::new("no measurements", (40, 60), ("sans-serif", 20)))
                .map_err(err)?;
            return Ok(());
        }
        let (tlo, thi) = self.points.iter().fold((f64::MAX, f64::MIN), |(a, b), p| {
            let lo = p.ideal_ms.filter(|v| *v > 0.0).unwrap_or(p.frame_ms);
            (a.min(p.frame_ms).min(lo), b.max(p.frame_ms))
        });
        let fhi = self.points.iter().map(|p| p.flip).fold(0.0, f64::max);
        let mut chart = log_flip_chart(
            root,
            &title,
            (tlo, thi),
            fhi,
            "median frame time, ms (log scale)",
            "mean FLIP against the reference",
        )?;
        let mut front: Vec<&Point> = self.points.iter().filter(|p| p.pareto).collect();
        front.sort_by(|a, b| a.frame_ms.total_cmp(&b.frame_ms));
        chart
            .draw_series(LineSeries::new(
                front.iter().map(|p| (p.frame_ms, p.flip)),
                colour(1).stroke_width(2),
            ))
            .map_err(err)?
            .label("Pareto front")
            .legend(|(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour(1).stroke_width(2))
            });
        let ideal = self.beside(|p| p.ideal_ms);
        if !ideal.is_empty() {
            let c = colour(3);
            for (p, i) in &ideal {
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        vec![(*i, p.flip), (p.frame_ms, p.flip)],
                        c.mix(0.5).stroke_width(1),
                    )))
                    .map_err(err)?;
            }
            chart
                .draw_series(
                    ideal
                        .iter()
                        .map(|(p, i)| Circle::new((*i, p.flip), 5, c.stroke_width(2))),
                )
                .map_err(err)?
                .label("ideal: full × shaded share")
                .legend(move |(x, y)| Circle::new((x + 10, y), 5, c.stroke_width(2)));
        }
        let bound = self.beside(|p| p.bound_ms);
        if !bound.is_empty() {
            let c = colour(2);
            chart
                .draw_series(
                    bound
                        .iter()
                        .map(|(p, b)| TriangleMarker::new((*b, p.flip), 6, c.stroke_width(2))),
                )
                .map_err(err)?
                .label("bound: foveation's passes free, shading × shaded share")
                .legend(move |(x, y)| TriangleMarker::new((x + 10, y), 6, c.stroke_width(2)));
        }
        for (preset, name) in [(true, "preset"), (false, "other configuration")] {
            let c = if preset { colour(0) } else { colour(5) };
            let size = if preset { 6 } else { 4 };
            chart
                .draw_series(
                    self.points
                        .iter()
                        .filter(|p| p.preset == preset)
                        .map(|p| Circle::new((p.frame_ms, p.flip), size, c.filled())),
                )
                .map_err(err)?
                .label(name)
                .legend(move |(x, y)| Circle::new((x + 10, y), size, c.filled()));
        }
        // The legend goes to the corner that covers the fewest points (measured and ideal),
        // and labels keep out of it.
        let marks: Vec<(i32, i32)> = self
            .points
            .iter()
            .map(|p| (p.frame_ms, p.flip))
            .chain(ideal.iter().map(|(p, i)| (*i, p.flip)))
            .chain(bound.iter().map(|(p, b)| (*b, p.flip)))
            .map(|xy| chart.backend_coord(&xy))
            .collect();
        let (xs, ys) = chart.plotting_area().get_pixel_range();
        let (corner, legend_box) = legend_corner(&marks, (xs.start, xs.end), (ys.start, ys.end));
        // Labels: presets first, then the rest of the front; each takes the first spot around
        // its point that overlaps no label already placed, or is left out.
        let mut placed: Vec<(i32, i32, i32, i32)> = vec![legend_box];
        let mut labelled: Vec<&Point> = self.points.iter().filter(|p| p.preset).collect();
        labelled.extend(self.points.iter().filter(|p| p.pareto && !p.preset));
        for p in labelled {
            let (px, py) = chart.backend_coord(&(p.frame_ms, p.flip));
            let w = 7 * p.name.chars().count() as i32 + 4;
            let spots = [
                (8, -18),
                (8, 6),
                (-w - 8, -18),
                (-w - 8, 6),
                (-w / 2, -26),
                (-w / 2, 12),
            ];
            let free = spots.iter().find(|(dx, dy)| {
                let b = (px + dx, py + dy, px + dx + w, py + dy + 15);
                let (wmax, hmax) = root.dim_in_pixel();
                b.0 >= 0
                    && b.2 <= wmax as i32
                    && b.1 >= 0
                    && b.3 <= hmax as i32
                    && !placed
                        .iter()
                        .any(|o| b.0 < o.2 && o.0 < b.2 && b.1 < o.3 && o.1 < b.3)
            });
            let Some(&(dx, dy)) = free else { continue };
            placed.push((px + dx, py + dy, px + dx + w, py + dy + 15));
            let style = ("sans-serif", 12).into_font().style(if p.preset {
                FontStyle::Bold
            } else {
                FontStyle::Normal
            });
            chart
                .draw_series(std::iter::once(
                    EmptyElement::at((p.frame_ms, p.flip))
                        + Text::new(p.name.clone(), (dx, dy), style),
                ))
                .map_err(err)?;
        }
        legend(&mut chart, corner)?;
        Ok(())
    }
}

/// Room the bench plot's legend takes (four entries), in pixels.
const LEGEND_SIZE: (i32, i32) = (200, 85);

/// The corner of the plotting area (x and y pixel ranges) whose legend-sized box holds the
/// fewest of `marks`, the first of upper right, upper left, lower left, lower right on a tie,
/// with that box (left, top, right, bottom).
fn legend_corner(
    marks: &[(i32, i32)],
    xs: (i32, i32),
    ys: (i32, i32),
) -> (SeriesLabelPosition, (i32, i32, i32, i32)) {
    let (w, h) = LEGEND_SIZE;
    let (left, right) = (xs.0, xs.1 - w);
    let (top, bottom) = (ys.0, ys.1 - h);
    let corners = [
        (SeriesLabelPosition::UpperRight, (right, top)),
        (SeriesLabelPosition::UpperLeft, (left, top)),
        (SeriesLabelPosition::LowerLeft, (left, bottom)),
        (SeriesLabelPosition::LowerRight, (right, bottom)),
    ];
    let covered = |(x, y): (i32, i32)| {
        marks
            .iter()
            .filter(|(mx, my)| (x - 8..x + w + 8).contains(mx) && (y - 8..y + h + 8).contains(my))
            .count()
    };
    let (at, (x, y)) = corners
        .into_iter()
        .min_by_key(|(_, xy)| covered(*xy))
        .unwrap_or((SeriesLabelPosition::UpperRight, (right, top)));
    (at, (x, y, x + w, y + h))
}

#[cfg(test)]
mod tests {
    use super::{legend_corner, tick_label};
    use plotters::prelude::SeriesLabelPosition;

    #[test]
    fn the_legend_goes_where_the_points_are_not() {
        use SeriesLabelPosition::{LowerLeft, UpperLeft, UpperRight};
        let (xs, ys) = ((60, 960), (40, 600));
        assert_eq!(legend_corner(&[], xs, ys).0, UpperRight);
        assert_eq!(legend_corner(&[(900, 60)], xs, ys).0, UpperLeft);
        let (at, b) = legend_corner(&[(900, 60), (80, 50)], xs, ys);
        assert_eq!(at, LowerLeft);
        assert_eq!(
            (b.0, b.3),
            (60, 600),
            "the box sits in the lower-left corner"
        );
    }

    #[test]
    fn ticks_below_one_keep_their_digits() {
        let labels: Vec<String> = [0.05, 0.1, 0.2, 0.5, 1.0, 2.0, 500.0, 2000.0]
            .into_iter()
            .map(tick_label)
            .collect();
        assert_eq!(
            labels,
            ["0.05", "0.1", "0.2", "0.5", "1", "2", "500", "2000"]
        );
    }
}
