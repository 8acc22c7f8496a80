//! The sweep's results: one record per configuration and group, the Pareto front, and the JSON,
//! Markdown and SVG files.

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::protocol::{Codec, Display};
use crate::quality::Errors;
use crate::settings::RenderSettings;

/// Median and 10th/90th percentiles (nearest rank) of a set of samples.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Spread {
    pub median: f64,
    pub p10: f64,
    pub p90: f64,
}

impl Spread {
    pub fn of(values: &[f64]) -> Spread {
        let mut v: Vec<f64> = values.iter().copied().filter(|x| !x.is_nan()).collect();
        if v.is_empty() {
            return Spread {
                median: f64::NAN,
                p10: f64::NAN,
                p90: f64::NAN,
            };
        }
        v.sort_by(|a, b| a.total_cmp(b));
        let at = |q: f64| v[((q * (v.len() - 1) as f64).round() as usize).min(v.len() - 1)];
        Spread {
            median: at(0.5),
            p10: at(0.1),
            p90: at(0.9),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BenchRecord {
    pub config: String,
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub gaze: [f32; 2],
    pub moving_gaze: bool,
    pub settings: RenderSettings,
    pub codec: Codec,
    pub quality: u8,
    pub frames: usize,
    /// Wall time from submitting the frame's passes to the GPU finishing them.
    pub frame_ms: Spread,
    /// Median GPU milliseconds per pass (timestamp queries).
    pub passes_ms: BTreeMap<String, f64>,
    pub encode_ms: Spread,
    pub bytes: f64,
    pub sampled: f64,
    /// Medians over the measured frames, against the reference render of each frame.
    pub errors: Errors,
    /// Medians against the physical ground truth (`--against`), when given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground_truth: Option<Errors>,
    /// full's median frame time over this one's, same group, same run.
    pub speedup_vs_full: Option<f64>,
    /// The same ratio for the shading pass alone.
    pub shade_speedup_vs_full: Option<f64>,
    /// GPU milliseconds of the passes foveation adds ([`FOVEATION_PASSES`]).
    #[serde(default)]
    pub overhead_ms: f64,
    /// The ratio to `full` if a frame cost in proportion to the samples it shades: 1 / shaded.
    #[serde(default)]
    pub ideal_vs_full: Option<f64>,
    /// The ratio to `full` if foveation's own passes were free and shading cost in proportion
    /// to the samples shaded, every other pass staying what `full` pays: [`super::bound_vs_full`].
    #[serde(default)]
    pub bound_vs_full: Option<f64>,
    /// Medians against the `full` render of the same frame (when `full` is in the sweep): what
    /// foveation costs in quality, apart from the shading model's own error.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vs_full: Option<Errors>,
    /// On the Pareto front of (frame time, FLIP) within its group.
    pub pareto: bool,
}

/// The passes a foveated frame adds to a full one: choosing, listing and reconstructing samples.
pub const FOVEATION_PASSES: [&str; 6] = [
    "sampling",
    "compact",
    "jfa",
    "resolve",
    "pull_push_tiles",
    "pull_push",
];

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Machine {
    pub adapter: String,
    /// How pass times were measured.
    pub timing: String,
    pub cpus: usize,
    pub os: String,
}

impl Machine {
    pub fn describe(renderer: &crate::render::Renderer) -> Machine {
        Machine {
            adapter: renderer.adapter(),
            timing: if renderer.timestamps() {
                "GPU timestamp queries per pass; frame time is wall clock from submit to GPU idle"
                    .into()
            } else {
                "no timestamp queries on this adapter: frame time (wall clock, submit to GPU idle) only".into()
            },
            cpus: std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1),
            os: format!("{} {}", std::env::consts::OS, std::env::consts::ARCH),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BenchReport {
    pub machine: Machine,
    pub seconds: f64,
    /// Stopped early (Ctrl-C); the records cover the groups finished or started.
    pub interrupted: bool,
    pub warmup: u32,
    pub frames: u32,
    pub display: Display,
    pub records: Vec<BenchRecord>,
    /// The ground-truth image (`--against`), if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground_truth: Option<String>,
    /// Our reference rung against that image, per group of its size.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub reference_truth: Vec<ReferenceTruth>,
}

/// How far our own reference (the model's best) is from physical ground truth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReferenceTruth {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub gaze: [f32; 2],
    pub errors: Errors,
}

pub(super) type GroupKey = (String, u32, u32, [u32; 2]);

pub(super) fn group_of(r: &BenchRecord) -> GroupKey {
    (
        r.scene.clone(),
        r.width,
        r.height,
        [r.gaze[0].to_bits(), r.gaze[1].to_bits()],
    )
}

/// Indices of the points not dominated by another (lower or equal cost and error, one strictly).
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    (0..points.len())
        .filter(|&i| {
            let (ci, ei) = points[i];
            !points
                .iter()
                .enumerate()
                .any(|(j, &(cj, ej))| j != i && cj <= ci && ej <= ei && (cj < ci || ej < ei))
        })
        .collect()
}

impl BenchReport {
    /// Fills in speedups against `full` and the Pareto flags, group by group.
    pub fn finish(&mut self) {
        let keys: Vec<GroupKey> = self.records.iter().map(group_of).collect();
        let mut groups: BTreeMap<GroupKey, Vec<usize>> = BTreeMap::new();
        for (i, k) in keys.into_iter().enumerate() {
            groups.entry(k).or_default().push(i);
        }
        for members in groups.values() {
            let full = members
                .iter()
                .map(|&i| &self.records[i])
                .find(|r| r.config == "full")
                .cloned();
            let points: Vec<(f64, f64)> = members
                .iter()
                .map(|&i| (self.records[i].frame_ms.median, self.records[i].errors.flip))
                .collect();
            let front = pareto_front(&points);
            for (slot, &i) in members.iter().enumerate() {
                let r = &mut self.records[i];
                r.overhead_ms = FOVEATION_PASSES
                    .iter()
                    .filter_map(|p| r.passes_ms.get(*p))
                    .sum();
                r.ideal_vs_full =
                    (r.settings.foveation.enabled && r.sampled > 0.0).then(|| 1.0 / r.sampled);
                if let Some(f) = &full {
                    r.speedup_vs_full = Some(f.frame_ms.median / r.frame_ms.median);
                    if let (Some(a), Some(b)) = (f.passes_ms.get("shade"), r.passes_ms.get("shade"))
                    {
                        r.shade_speedup_vs_full = (*b > 0.0).then(|| a / b);
                    }
                    if let (Some(a), true) = (f.passes_ms.get("shade"), r.ideal_vs_full.is_some()) {
                        r.bound_vs_full = super::bound_vs_full(f.frame_ms.median, *a, r.sampled);
                    }
                }
                r.pareto = front.contains(&slot);
            }
        }
    }

    pub fn markdown(&self) -> String {
        let mut s = String::new();
        s.push_str(&format!(
            "# fovea bench\n\nAdapter: {}  \nTiming: {}  \nCPUs: {}, {}. {} warm-up + {} measured frames per configuration, interleaved; {:.0} s{}.\n\n",
            self.machine.adapter,
            self.machine.timing,
            self.machine.cpus,
            self.machine.os,
            self.warmup,
            self.frames,
            self.seconds,
            if self.interrupted { " (interrupted: partial results)" } else { "" }
        ));
        s.push_str("Errors are medians against the reference render of the same frame; *pooled* weights each pixel by min(1, pixel angle / MAR(e)), *5°* is the disc within 5° of the gaze. Times are medians (10th–90th percentile). ★ marks the Pareto front of (frame time, FLIP).\n");
        let mut last: Option<GroupKey> = None;
        for r in &self.records {
            let key = group_of(r);
            if last.as_ref() != Some(&key) {
                s.push_str(&format!(
                    "\n## {} {}×{}, gaze ({:.2}, {:.2}){}\n\n",
                    r.scene,
                    r.width,
                    r.height,
                    r.gaze[0],
                    r.gaze[1],
                    if r.moving_gaze { " moving" } else { "" }
                ));
                s.push_str("| | configuration | shaded | frame ms | vs full | shade ms | PSNR dB | SSIM | FLIP | FLIP pooled | FLIP 5° | encode ms | KiB |\n");
                s.push_str("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
                last = Some(key);
            }
            let e = &r.errors;
            s.push_str(&format!(
                "| {} | {} | {:.1}% | {:.1} ({:.1}–{:.1}) | {} | {} | {:.2} | {:.4} | {:.4} | {:.4} | {:.4} | {:.2} | {:.1} |\n",
                if r.pareto { "★" } else { "" },
                r.config,
                100.0 * r.sampled,
                r.frame_ms.median,
                r.frame_ms.p10,
                r.frame_ms.p90,
                r.speedup_vs_full.map(|x| format!("{x:.2}×")).unwrap_or_else(|| "–".into()),
                r.passes_ms.get("shade").map(|x| format!("{x:.2}")).unwrap_or_else(|| "–".into()),
                e.psnr,
                e.ssim,
                e.flip,
                e.flip_pooled,
                e.flip_fovea,
                r.encode_ms.median,
                r.bytes / 1024.0,
            ));
        }
        s.push_str(&self.distance_to_ideal());
        s.push_str(&self.per_pass());
        if let Some(file) = &self.ground_truth {
            s.push_str(&format!(
                "\n## Against physical ground truth `{file}`\n\nMedians over the measured frames; the model's own reference first.\n\n| group | configuration | PSNR dB | SSIM | FLIP | FLIP pooled | FLIP 5° |\n|---|---|---:|---:|---:|---:|---:|\n"
            ));
            let row = |s: &mut String, group: String, name: &str, e: &Errors| {
                s.push_str(&format!(
                    "| {group} | {name} | {:.2} | {:.4} | {:.4} | {:.4} | {:.4} |\n",
                    e.psnr, e.ssim, e.flip, e.flip_pooled, e.flip_fovea
                ));
            };
            for t in &self.reference_truth {
                let group = format!(
                    "{} {}×{} ({:.2}, {:.2})",
                    t.scene, t.width, t.height, t.gaze[0], t.gaze[1]
                );
                row(
                    &mut s,
                    group.clone(),
                    "reference (brute-force dipole)",
                    &t.errors,
                );
                for r in self.records.iter().filter(|r| {
                    r.scene == t.scene
                        && r.width == t.width
                        && r.height == t.height
                        && r.gaze == t.gaze
                }) {
                    if let Some(e) = &r.ground_truth {
                        row(&mut s, group.clone(), &r.config, e);
                    }
                }
            }
        }
        s
    }
}

/// Writes `bench.json`, `bench.md`, and the cost-vs-error plot as `bench.svg` and `bench.png`.
pub fn write_reports(report: &BenchReport, dir: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    let json = serde_json::to_string_pretty(report).map_err(std::io::Error::other)?;
    write_atomic(&dir.join("bench.json"), json.as_bytes())?;
    write_atomic(&dir.join("bench.md"), report.markdown().as_bytes())?;
    crate::plot::write(
        &crate::plot::bench::BenchPlot::of(report),
        &dir.join("bench"),
    )
    .map_err(std::io::Error::other)?;
    Ok(())
}

/// Write to a temporary file and rename, so an interrupted run never leaves half a report.
pub(super) fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, bytes)?;
    std::fs::rename(tmp, path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pareto_front_keeps_only_undominated_points() {
        let pts = [
            (10.0, 0.0),
            (5.0, 0.1),
            (6.0, 0.2),
            (1.0, 0.5),
            (1.0, 0.6),
            (5.0, 0.1),
        ];
        // (6, 0.2) is dominated by (5, 0.1); (1, 0.6) by (1, 0.5); equal points both stay.
        assert_eq!(pareto_front(&pts), vec![0, 1, 3, 5]);
    }

    #[test]
    fn spread_uses_nearest_ranks_and_ignores_nan() {
        let s = Spread::of(&[5.0, 1.0, f64::NAN, 3.0, 2.0, 4.0]);
        assert_eq!((s.median, s.p10, s.p90), (3.0, 1.0, 5.0));
        assert!(Spread::of(&[]).median.is_nan());
    }
}
