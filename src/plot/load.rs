//! The load plots: gaze-to-frame latency percentiles and frames per second per session against
//! the number of sessions (one point per run of a sweep), and one run's frame rate over time.

use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use serde::Deserialize;

use super::{colour, err, legend, linear_tick, padded, Plot};

/// One run of `fovea load`, as its report (and `load.json`) records it.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct Run {
    pub sessions: usize,
    pub seconds: f64,
    pub fps_total: f64,
    pub fps_min: f64,
    pub fps_max: f64,
    /// Each session's frames over its own active time (absent from older reports).
    #[serde(default)]
    pub fps_per_session: Vec<f64>,
    pub latency_ms: Latency,
    /// Frames received per second of the run, all sessions together.
    pub fps_timeline: Vec<u64>,
}

impl Run {
    /// The mean session's frame rate, over each session's active time as the slowest and
    /// fastest are (the total over the whole run, ramp-up included, fell below the slowest).
    fn mean_fps(&self) -> f64 {
        if self.fps_per_session.is_empty() {
            return self.fps_total / self.sessions.max(1) as f64;
        }
        self.fps_per_session.iter().sum::<f64>() / self.fps_per_session.len() as f64
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct Latency {
    pub p50: f64,
    pub p95: f64,
    pub p99: f64,
}

/// Latency and frame rate against sessions, side by side.
pub struct SweepPlot {
    pub title: String,
    pub runs: Vec<Run>,
}

/// Frames per second over one run; the last, partial second is left out (it would look like
/// an outage).
pub struct TimelinePlot {
    pub title: String,
    pub run: Run,
}

impl Plot for SweepPlot {
    fn size(&self) -> (u32, u32) {
        (1100, 480)
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
        let x = SessionAxis::new(&self.runs);
        let lmax = self
            .runs
            .iter()
            .map(|r| r.latency_ms.p99)
            .filter(|v| v.is_finite())
            .fold(1.0, f64::max);
        let y = value_axis(lmax);
        let mut chart = ChartBuilder::on(&left)
            .margin(14)
            .x_label_area_size(44)
            .y_label_area_size(64)
            .caption("gaze → frame latency", ("sans-serif", 15))
            .build_cartesian_2d(x.clone(), y.clone())
            .map_err(err)?;
        mesh(&mut chart, "ms")?;
        let series: [Series; 3] = [
            ("p50", |r| r.latency_ms.p50),
            ("p95", |r| r.latency_ms.p95),
            ("p99", |r| r.latency_ms.p99),
        ];
        for (i, (name, f)) in series.iter().enumerate() {
            self.line(&mut chart, name, i, f)?;
        }
        legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
        let fmax = self.runs.iter().map(|r| r.fps_max).fold(1.0, f64::max);
        let y = value_axis(fmax);
        let mut chart = ChartBuilder::on(&right)
            .margin(14)
            .x_label_area_size(44)
            .y_label_area_size(64)
            .caption("frames per second, per session", ("sans-serif", 15))
            .build_cartesian_2d(x.clone(), y.clone())
            .map_err(err)?;
        mesh(&mut chart, "frames per second")?;
        let series: [Series; 3] = [
            ("slowest session", |r| r.fps_min),
            ("mean", Run::mean_fps),
            ("fastest session", |r| r.fps_max),
        ];
        for (i, (name, f)) in series.iter().enumerate() {
            self.line(&mut chart, name, i, f)?;
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        Ok(())
    }
}

/// The sessions axis: ticks at the counts that were run (1, 2, 4, 8 rather than every integer
/// up to 8) and half a session either side, so a single run sits in the middle with one tick
/// under it instead of between unlabelled fractions of a session. (plotters' own key-point
/// wrapper drops the label formatting an f64 axis needs, hence this small axis of our own.)
#[derive(Clone)]
struct SessionAxis {
    linear: RangedCoordf64,
    ticks: Vec<f64>,
}

impl SessionAxis {
    fn new(runs: &[Run]) -> Self {
        let mut ticks: Vec<f64> = runs.iter().map(|r| r.sessions as f64).collect();
        ticks.sort_by(f64::total_cmp);
        ticks.dedup();
        let (lo, hi) = match (ticks.first(), ticks.last()) {
            (Some(lo), Some(hi)) => (*lo, *hi),
            _ => (1.0, 1.0),
        };
        let linear = ((lo - 0.5)..(hi + 0.5)).into();
        SessionAxis { linear, ticks }
    }
}

impl Ranged for SessionAxis {
    type ValueType = f64;
    type FormatOption = DefaultFormatting;

    fn range(&self) -> std::ops::Range<f64> {
        self.linear.range()
    }

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        self.linear.map(value, limit)
    }

    fn key_points<Hint: KeyPointHint>(&self, _hint: Hint) -> Vec<f64> {
        self.ticks.clone()
    }
}

/// A value axis from zero with the top third left free: the legends sit up there, and every
/// point of a run (the fastest session's, say) would otherwise be able to hide behind one.
fn value_axis(max: f64) -> std::ops::Range<f64> {
    let r = padded(0.0, max, false);
    r.start..(r.start + (r.end - r.start) * 1.3)
}

/// A line of the sweep plot: its legend text and what it reads from each run.
type Series = (&'static str, fn(&Run) -> f64);

type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<SessionAxis, RangedCoordf64>>;

fn mesh<'a, DB: DrawingBackend + 'a>(chart: &mut Chart<'a, DB>, y: &str) -> Result<(), String> {
    chart
        .configure_mesh()
        .light_line_style(WHITE.mix(0.0))
        .y_label_formatter(&|v| linear_tick(*v))
        .x_desc("sessions")
        .y_desc(y)
        .axis_desc_style(("sans-serif", 14))
        .label_style(("sans-serif", 12))
        .x_label_formatter(&|v| linear_tick(*v))
        .draw()
        .map_err(err)
}

impl SweepPlot {
    fn line<'a, DB: DrawingBackend + 'a>(
        &self,
        chart: &mut Chart<'a, DB>,
        name: &str,
        i: usize,
        f: &fn(&Run) -> f64,
    ) -> Result<(), String> {
        let c = colour(i);
        let pts: Vec<(f64, f64)> = self
            .runs
            .iter()
            .map(|r| (r.sessions as f64, f(r)))
            .filter(|(_, v)| v.is_finite())
            .collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))
            .map_err(err)?
            .label(name.to_string())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
        chart
            .draw_series(pts.into_iter().map(|p| Circle::new(p, 4, c.filled())))
            .map_err(err)?;
        Ok(())
    }
}

impl TimelinePlot {
    /// Whole seconds only: the timeline's last bucket covers a fraction of a second.
    pub fn seconds(&self) -> Vec<(f64, f64)> {
        let whole = self.run.seconds.floor() as usize;
        self.run
            .fps_timeline
            .iter()
            .take(whole.min(self.run.fps_timeline.len()))
            .enumerate()
            .map(|(s, n)| (s as f64 + 0.5, *n as f64))
            .collect()
    }
}

impl Plot for TimelinePlot {
    fn size(&self) -> (u32, u32) {
        (900, 360)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        root.fill(&WHITE).map_err(err)?;
        let pts = self.seconds();
        let ymax = pts.iter().map(|p| p.1).fold(1.0, f64::max);
        let mut chart = ChartBuilder::on(root)
            .caption(
                &self.title,
                ("sans-serif", 16).into_font().style(FontStyle::Bold),
            )
            .margin(14)
            .x_label_area_size(44)
            .y_label_area_size(64)
            .build_cartesian_2d(
                0.0..(self.run.seconds.floor().max(1.0)),
                padded(0.0, ymax, false),
            )
            .map_err(err)?;
        chart
            .configure_mesh()
            .light_line_style(WHITE.mix(0.0))
            .x_label_formatter(&|v| linear_tick(*v))
            .y_label_formatter(&|v| linear_tick(*v))
            .x_desc("seconds into the run")
            .y_desc("frames per second, all sessions")
            .axis_desc_style(("sans-serif", 14))
            .label_style(("sans-serif", 12))
            .draw()
            .map_err(err)?;
        chart
            .draw_series(LineSeries::new(pts, colour(0).stroke_width(2)))
            .map_err(err)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(sessions: usize, p95: f64) -> Run {
        Run {
            sessions,
            seconds: 3.0,
            fps_total: 20.0,
            fps_min: 9.0,
            fps_max: 11.0,
            fps_per_session: Vec::new(),
            latency_ms: Latency {
                p50: p95 / 2.0,
                p95,
                p99: p95 * 1.2,
            },
            fps_timeline: vec![20, 21, 19],
        }
    }

    #[test]
    fn the_mean_session_lies_between_the_slowest_and_the_fastest() {
        // An H200 run: 333 fps over the whole 8-session run, ramp-up included, is 41.7 per
        // session, below the slowest session's 43.3 over its own active time.
        let mut r = run(8, 100.0);
        (r.fps_total, r.fps_min, r.fps_max) = (333.26, 43.29, 45.81);
        assert!(r.mean_fps() < r.fps_min, "old reports keep the old mean");
        r.fps_per_session = vec![43.29, 45.81, 44.0, 44.5, 43.9, 45.0, 44.2, 43.8];
        let mean = r.mean_fps();
        assert!((r.fps_min..=r.fps_max).contains(&mean), "{mean}");
    }

    #[test]
    fn the_sweep_plot_writes_an_svg_with_ticks_and_units_and_a_png() {
        let dir = std::env::temp_dir().join(format!("fovea-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let plot = SweepPlot {
            title: "test sweep".into(),
            runs: vec![run(1, 100.0), run(2, 180.0), run(4, 390.0)],
        };
        crate::plot::write(&plot, &dir.join("load")).unwrap();
        let svg = std::fs::read_to_string(dir.join("load.svg")).unwrap();
        // Texts sit on lines of their own; "4" is a tick of the sessions axis, "300" of the ms one.
        for text in [
            "test sweep",
            "sessions",
            "frames per second",
            "p95",
            "\n4\n<",
            "\n300\n<",
        ] {
            assert!(svg.contains(text), "the SVG lacks {text:?}");
        }
        let png = image::open(dir.join("load.png")).unwrap();
        assert_eq!((png.width(), png.height()), plot.size());
        // Not blank: the lines and labels put dark pixels on the white background.
        let dark = png.to_luma8().pixels().filter(|p| p.0[0] < 100).count();
        assert!(dark > 2000, "{dark} dark pixels");
    }

    #[test]
    fn the_sessions_axis_ticks_the_counts_run_and_centres_a_single_run() {
        let one = SessionAxis::new(&[run(2, 100.0)]);
        assert_eq!((one.range(), one.key_points(10)), (1.5..2.5, vec![2.0]));
        let sweep = SessionAxis::new(&[run(4, 1.0), run(1, 1.0), run(8, 1.0), run(2, 1.0)]);
        assert_eq!(sweep.range(), 0.5..8.5);
        assert_eq!(sweep.key_points(10), vec![1.0, 2.0, 4.0, 8.0]);
        assert_eq!(SessionAxis::new(&[]).key_points(10), Vec::<f64>::new());
    }

    #[test]
    fn the_top_of_a_value_axis_is_left_to_the_legend() {
        // The 3 fps of a software-adapter run hid behind the "fastest session" legend.
        for max in [0.3, 3.0, 3.025, 47.0, 1740.0] {
            let y = value_axis(max);
            let height = (max - y.start) / (y.end - y.start);
            assert!(
                y.start <= 0.0 && (0.6..=0.75).contains(&height),
                "{max}: {y:?}"
            );
        }
    }

    #[test]
    fn ticks_carry_the_decimals_they_need_and_no_more() {
        let cases = [
            (0.0, "0"),
            (3.0, "3"),
            (1500.0, "1500"),
            (2.5, "2.5"),
            (0.25, "0.25"),
            (0.1 + 0.2, "0.3"),
            (-1.0, "-1"),
            (1.0 / 3.0, "0.33"),
        ];
        for (v, text) in cases {
            assert_eq!(linear_tick(v), text, "{v}");
        }
    }

    #[test]
    fn the_partial_last_second_is_not_plotted_as_an_outage() {
        let run = Run {
            sessions: 2,
            seconds: 3.4,
            fps_total: 20.0,
            fps_min: 9.0,
            fps_max: 11.0,
            fps_per_session: Vec::new(),
            latency_ms: Latency {
                p50: 10.0,
                p95: 20.0,
                p99: 30.0,
            },
            fps_timeline: vec![20, 21, 19, 3],
        };
        let t = TimelinePlot {
            title: String::new(),
            run,
        };
        assert_eq!(t.seconds(), vec![(0.5, 20.0), (1.5, 21.0), (2.5, 19.0)]);
    }
}
