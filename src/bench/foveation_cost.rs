//! Foveation against `full` in the bench's Markdown: per configuration, what foveation adds,
//! the achieved ratio beside the bound and the ideal, and every pass's GPU time per group.

use super::report::{group_of, BenchRecord, BenchReport, GroupKey};
use crate::render::cost::WORTH_SAVING;
use crate::render::frame::PASSES;

/// What a foveated frame shading `shaded` of the pixels could reach against `full` (frame and
/// shading pass `full_frame_ms`, `full_shade_ms`) with foveation's own passes free: the
/// shading falls with the samples, the G-buffer, output and the rest do not. The ideal
/// 1 / shaded lets those fall too; between this bound and it lie the passes foveation cannot
/// thin out, between the achieved ratio and this bound foveation's overhead and samples that
/// cost more than the average pixel.
pub fn bound_vs_full(full_frame_ms: f64, full_shade_ms: f64, shaded: f64) -> Option<f64> {
    let shaded = shaded.clamp(0.0, 1.0);
    let frame = full_frame_ms - (1.0 - shaded) * full_shade_ms;
    (full_frame_ms > 0.0 && full_shade_ms >= 0.0 && frame > 0.0).then(|| full_frame_ms / frame)
}

impl BenchReport {
    /// Per foveated configuration: what foveation adds, the achieved ratio to `full` beside the
    /// ideal one, and the quality lost against `full` itself.
    pub(super) fn distance_to_ideal(&self) -> String {
        let rows: Vec<&BenchRecord> = self
            .records
            .iter()
            .filter(|r| r.ideal_vs_full.is_some() && r.speedup_vs_full.is_some())
            .collect();
        if rows.is_empty() {
            return String::new();
        }
        let mut s = String::from(
            "\n## Foveation against full: cost and distance to the ideal\n\n*Overhead* is the GPU time of the passes foveation adds (sampling, compaction, reconstruction), also as a share of `full`'s frame; *ideal* is the ratio if a frame cost in proportion to the pixels it shades (1 / shaded); *bound* the ratio if foveation's own passes were free and shading cost in proportion to the pixels shaded while every other pass (the G-buffer, output) cost what it does in `full`, so achieved / bound is what foveation's overhead and its costlier samples leave; errors are against the `full` render of the same frame; *server* is what the render thread would do with such frames: foveate them, or shade them whole where foveating saves under 5% (`render::cost::WORTH_SAVING`).\n\n| group | configuration | shaded | overhead ms | overhead / full | achieved | bound | ideal | achieved / bound | server | PSNR vs full | FLIP vs full | FLIP 5° vs full |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|\n",
        );
        for r in rows {
            let (achieved, bound, ideal) = (
                r.speedup_vs_full.unwrap_or(f64::NAN),
                r.bound_vs_full.unwrap_or(f64::NAN),
                r.ideal_vs_full.unwrap_or(f64::NAN),
            );
            let full_ms = r.frame_ms.median * achieved;
            let (psnr, flip, flip5) =
                r.vs_full
                    .as_ref()
                    .map_or(("–".into(), "–".into(), "–".into()), |e| {
                        (
                            format!("{:.2}", e.psnr),
                            format!("{:.4}", e.flip),
                            format!("{:.4}", e.flip_fovea),
                        )
                    });
            // The same test as `cost::Verdict::pays`, against `full`'s frame.
            let server = if achieved * (1.0 - WORTH_SAVING) > 1.0 {
                "foveates"
            } else {
                "shades whole"
            };
            s.push_str(&format!(
                "| {} {}×{} ({:.2}, {:.2}) | {} | {:.1}% | {:.1} | {:.0}% | {:.2}× | {:.2}× | {:.1}× | {:.0}% | {server} | {psnr} | {flip} | {flip5} |\n",
                r.scene, r.width, r.height, r.gaze[0], r.gaze[1], r.config,
                100.0 * r.sampled, r.overhead_ms, 100.0 * r.overhead_ms / full_ms,
                achieved, bound, ideal, 100.0 * achieved / bound,
            ));
        }
        s
    }
}

impl BenchReport {
    /// Per group: every pass's median GPU ms under each configuration, the frame, and the
    /// overhead beside the ideal, so a change to one pass is measured on that pass.
    pub(super) fn per_pass(&self) -> String {
        let mut groups: Vec<(GroupKey, Vec<&BenchRecord>)> = Vec::new();
        for r in &self.records {
            let key = group_of(r);
            match groups.iter_mut().find(|(k, _)| *k == key) {
                Some((_, rows)) => rows.push(r),
                None => groups.push((key, vec![r])),
            }
        }
        let mut s = String::from("\n## Per pass: GPU ms (medians)\n\n*Overhead* is what foveation adds (sampling, compaction, reconstruction) as a share of `full`'s frame; *ideal* is 1 / shaded; *bound* the ratio with foveation's passes free and only shading falling with the samples.\n");
        for (_, rows) in groups {
            let r0 = rows[0];
            let mut passes: Vec<&String> = rows.iter().flat_map(|r| r.passes_ms.keys()).collect();
            // Frame order, as `render::frame::PASSES` declares the passes; others after them.
            let rank = |p: &str| {
                PASSES
                    .iter()
                    .position(|q| q.label == p)
                    .unwrap_or(PASSES.len())
            };
            passes.sort_by(|a, b| rank(a).cmp(&rank(b)).then(a.cmp(b)));
            passes.dedup();
            s.push_str(&format!(
                "\n### {} {}×{}, gaze ({:.2}, {:.2})\n\n| pass (ms) |",
                r0.scene, r0.width, r0.height, r0.gaze[0], r0.gaze[1]
            ));
            for r in &rows {
                s.push_str(&format!(" {} |", r.config));
            }
            s.push_str(&format!("\n|---|{}\n", "---:|".repeat(rows.len())));
            let line = |s: &mut String, name: &str, cell: &dyn Fn(&BenchRecord) -> String| {
                s.push_str(&format!("| {name} |"));
                for r in &rows {
                    s.push_str(&format!(" {} |", cell(r)));
                }
                s.push('\n');
            };
            for p in passes {
                line(&mut s, p, &|r| {
                    r.passes_ms.get(p).map_or("–".into(), |v| format!("{v:.1}"))
                });
            }
            line(&mut s, "**frame**", &|r| {
                format!("**{:.0}**", r.frame_ms.median)
            });
            line(&mut s, "shaded", &|r| format!("{:.1}%", 100.0 * r.sampled));
            line(&mut s, "vs full (achieved / bound / ideal)", &|r| match (
                r.speedup_vs_full,
                r.bound_vs_full,
                r.ideal_vs_full,
            ) {
                (Some(a), Some(b), Some(i)) => format!("{a:.2}× / {b:.2}× / {i:.1}×"),
                (Some(a), None, Some(i)) => format!("{a:.2}× / – / {i:.1}×"),
                (Some(a), _, None) => format!("{a:.2}×"),
                _ => "–".into(),
            });
            line(&mut s, "PSNR / FLIP 5° vs full", &|r| {
                r.vs_full.as_ref().map_or("–".into(), |e| {
                    format!("{:.1} dB / {:.4}", e.psnr, e.flip_fovea)
                })
            });
            line(
                &mut s,
                "overhead / full frame",
                &|r| match r.speedup_vs_full {
                    Some(a) if r.overhead_ms > 0.0 => {
                        format!("{:.0}%", 100.0 * r.overhead_ms / (r.frame_ms.median * a))
                    }
                    _ => "–".into(),
                },
            );
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bound_lies_between_no_gain_and_the_shading_removed() {
        // A 100 ms frame of which 80 are shading.
        assert_eq!(bound_vs_full(100.0, 80.0, 1.0), Some(1.0));
        let none_shaded = bound_vs_full(100.0, 80.0, 0.0).unwrap();
        assert!((none_shaded - 5.0).abs() < 1e-12, "{none_shaded}");
        let quarter = bound_vs_full(100.0, 80.0, 0.25).unwrap();
        assert!((quarter - 100.0 / 40.0).abs() < 1e-12, "{quarter}");
        // Never above the ideal 1 / shaded, equal to it only if shading were the whole frame.
        for shaded in [0.01, 0.1, 0.5, 0.9] {
            let b = bound_vs_full(100.0, 80.0, shaded).unwrap();
            assert!(b > 1.0 && b < 1.0 / shaded, "{shaded}: {b}");
            let all = bound_vs_full(100.0, 100.0, shaded).unwrap();
            assert!((all - 1.0 / shaded).abs() < 1e-9, "{shaded}: {all}");
        }
        // Out-of-range shares are clamped; a frame that would cost nothing has no bound.
        assert_eq!(bound_vs_full(100.0, 80.0, 1.5), Some(1.0));
        assert_eq!(bound_vs_full(100.0, 100.0, 0.0), None);
        assert_eq!(bound_vs_full(0.0, 0.0, 0.5), None);
        assert_eq!(bound_vs_full(f64::NAN, 80.0, 0.5), None);
    }
}
