//! The codec sweep's results: one row per encoder configuration, the 4:2:0 floor, and each
//! family's bytes at equal foveal quality, read off its bytes-vs-FLIP curve.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::codec_configs::CodecConfig;
use super::report::{Machine, Spread};

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CodecRow {
    pub name: String,
    pub family: String,
    pub config: CodecConfig,
    /// Bytes per frame, keyframes excluded.
    pub bytes: Spread,
    /// The stream's first frame (H.264).
    pub keyframe_bytes: Option<f64>,
    /// kbit/s at 60 frames per second, a keyframe every two seconds included (H.264).
    pub kbps: f64,
    /// Mean FLIP within 5° of each frame's gaze, against the lossless frame.
    pub flip_fovea: f64,
    /// Mean FLIP over the whole frame.
    pub flip: f64,
    /// Wall time of the encode: low-pass, colour conversion and coding, on one core.
    pub encode_ms: Spread,
}

/// FLIP of a conversion alone (no codec): the best any 4:2:0 (or 4:4:4) codec can show.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FloorRow {
    pub name: String,
    pub flip_fovea: f64,
    pub flip: f64,
}

/// A family's bitrate (kbit/s at 60 fps, keyframes included) at the target's foveal FLIP.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", content = "bytes", rename_all = "snake_case")]
pub enum AtQuality {
    /// Between two measured configurations (log bitrate linear in FLIP).
    Interpolated(f64),
    /// Even the family's lowest bitrate beats the target: at most this.
    AtMost(f64),
    /// Even the family's highest bitrate misses the target.
    Unreached,
}

impl AtQuality {
    pub fn bytes(&self) -> Option<f64> {
        match self {
            AtQuality::Interpolated(b) | AtQuality::AtMost(b) => Some(*b),
            AtQuality::Unreached => None,
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EqualQuality {
    pub family: String,
    pub at: AtQuality,
    /// Bitrate over the target configuration's (JPEG q85).
    pub vs_target: Option<f64>,
    /// Bitrate over the same codec's without foveated encoding, at the same FLIP.
    pub vs_plain: Option<f64>,
    /// The same comparison at a stricter quality: the best foveal FLIP that both this family
    /// and the codec without foveated encoding reach. Around the target's FLIP the curves can
    /// be nearly flat, where a small difference in FLIP moves the read-off a lot; this second
    /// reading says whether the saving holds along the curve.
    #[serde(default)]
    pub at_strictest: Option<Strictest>,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Strictest {
    /// The higher of the two families' best (lowest) foveal FLIPs: both reach it.
    pub flip_fovea: f64,
    /// This family's bitrate there.
    pub at: AtQuality,
    /// That bitrate over the plain codec's there.
    pub vs_plain: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CodecReport {
    pub machine: Machine,
    pub scene: String,
    /// The preset the frames were rendered with (a session's default).
    pub preset: String,
    pub width: u32,
    pub height: u32,
    pub recording: String,
    /// The camera's turn rate (0: still); reports from before it existed read as still.
    #[serde(default)]
    pub orbit_deg_per_s: f64,
    pub frames: usize,
    pub fps: f64,
    pub seconds: f64,
    pub interrupted: bool,
    pub rows: Vec<CodecRow>,
    pub floors: Vec<FloorRow>,
    /// Against [`TARGET`]'s foveal FLIP.
    pub equal_quality: Vec<EqualQuality>,
}

/// The configuration whose foveal quality the others are matched to.
pub const TARGET: &str = "JPEG q85";

/// The bitrate (or bytes) at foveal FLIP `target` along a family's measured points (bitrate,
/// FLIP), read on the family's front: a point another one beats on both bitrate and FLIP is
/// left out, as a user would leave that configuration. FLIP need not fall with bitrate: a
/// low target can cost more and look worse (the rate guard freeing the quantiser: on
/// `gallery` H.264 at 250 kbit/s sent 1048 kbit/s at foveal FLIP 0.102, against 701 kbit/s
/// at 0.061 for 500). The first crossing of the front, from the lowest bitrate, is taken.
pub fn at_quality(points: &[(f64, f64)], target: f64) -> AtQuality {
    let mut p: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|(b, f)| *b > 0.0 && b.is_finite() && f.is_finite())
        .collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    // Walking up in bitrate, keep only points better than every cheaper one.
    let mut best = f64::INFINITY;
    p.retain(|&(_, f)| {
        let keep = f < best;
        best = best.min(f);
        keep
    });
    let Some(first) = p.first() else {
        return AtQuality::Unreached;
    };
    if first.1 <= target {
        return AtQuality::AtMost(first.0);
    }
    for pair in p.windows(2) {
        let ((b0, f0), (b1, f1)) = (pair[0], pair[1]);
        if f1 <= target {
            // f0 > target ≥ f1, so the denominator is positive.
            let s = (f0 - target) / (f0 - f1);
            return AtQuality::Interpolated((b0.ln() + s * (b1.ln() - b0.ln())).exp());
        }
    }
    AtQuality::Unreached
}

/// A foveated family against its plain codec at the best foveal FLIP both reach: none where
/// either has no finite point.
fn strictest(plain: &[(f64, f64)], here: &[(f64, f64)]) -> Option<Strictest> {
    let best = |pts: &[(f64, f64)]| {
        pts.iter()
            .filter(|p| p.0 > 0.0 && p.0.is_finite())
            .map(|p| p.1)
            .filter(|f| f.is_finite())
            .min_by(f64::total_cmp)
    };
    let flip = best(plain)?.max(best(here)?);
    let at = at_quality(here, flip);
    Some(Strictest {
        flip_fovea: flip,
        at,
        vs_plain: ratio(at, at_quality(plain, flip)),
    })
}

/// One bitrate over another, where both are known.
fn ratio(here: AtQuality, plain: AtQuality) -> Option<f64> {
    plain.bytes().zip(here.bytes()).map(|(p, b)| b / p)
}

impl CodecReport {
    /// Fills `equal_quality`: every family's bitrate at the target's foveal FLIP. Bitrates, not
    /// median frames, so H.264's keyframes count as they do on the wire.
    pub fn finish(&mut self) {
        self.equal_quality.clear();
        let Some(target) = self.rows.iter().find(|r| r.name == TARGET) else {
            return;
        };
        let (goal, goal_kbps) = (target.flip_fovea, target.kbps);
        let mut families: Vec<(&str, String)> = self
            .rows
            .iter()
            .map(|r| (r.family.as_str(), r.config.plain_family()))
            .collect();
        families.dedup();
        let points = |family: &str| -> Vec<(f64, f64)> {
            self.rows
                .iter()
                .filter(|r| r.family == family)
                .map(|r| (r.kbps, r.flip_fovea))
                .collect()
        };
        for (family, plain) in families {
            let here = at_quality(&points(family), goal);
            let foveated = plain != family;
            let at_strictest = foveated.then(|| strictest(&points(&plain), &points(family)));
            self.equal_quality.push(EqualQuality {
                family: family.to_string(),
                at: here,
                vs_target: here.bytes().map(|b| b / goal_kbps),
                vs_plain: foveated
                    .then(|| ratio(here, at_quality(&points(&plain), goal)))
                    .flatten(),
                at_strictest: at_strictest.flatten(),
            });
        }
    }

    /// ", the camera orbiting N°/s" where it turned, else nothing: for titles.
    pub fn camera_note(&self) -> String {
        if self.orbit_deg_per_s != 0.0 {
            format!(", the camera orbiting {}°/s", self.orbit_deg_per_s)
        } else {
            String::new()
        }
    }

    pub fn markdown(&self) -> String {
        let mut s = format!(
            "# Codecs on {} ({}) at {}×{}, {} frames along {}{} ({} fps)\n\n{} · {} CPUs · {:.0} s{}\n\n",
            self.scene,
            self.preset,
            self.width,
            self.height,
            self.frames,
            self.recording,
            self.camera_note(),
            self.fps,
            self.machine.adapter,
            self.machine.cpus,
            self.seconds,
            if self.interrupted {
                " · interrupted: partial results"
            } else {
                ""
            }
        );
        s.push_str("FLIP against the lossless frame; foveal = within 5° of each frame's gaze. Bytes per frame exclude the H.264 stream's first keyframe (a later one, where the rate guard switched ranges, counts as a frame); kbit/s adds one every 2 s.\n\n");
        s.push_str("| configuration | bytes/frame (median) | H.264 keyframe bytes | kbit/s at 60 fps | foveal FLIP | whole-frame FLIP | encode ms (median) |\n|---|---:|---:|---:|---:|---:|---:|\n");
        for r in &self.rows {
            let key = r.keyframe_bytes.map_or("–".into(), |k| format!("{k:.0}"));
            s.push_str(&format!(
                "| {} | {:.0} | {key} | {:.0} | {:.4} | {:.4} | {:.1} |\n",
                r.name, r.bytes.median, r.kbps, r.flip_fovea, r.flip, r.encode_ms.median
            ));
        }
        for f in &self.floors {
            s.push_str(&format!(
                "| {} | – | – | – | {:.4} | {:.4} | – |\n",
                f.name, f.flip_fovea, f.flip
            ));
        }
        if let Some(t) = self.rows.iter().find(|r| r.name == TARGET) {
            s.push_str(&format!(
                "\n## At {TARGET}'s foveal quality (FLIP {:.4}, {:.0} kbit/s)\n\nEach family's bitrate where its curve crosses that FLIP (log bitrate interpolated between the two configurations around it; a configuration another of the family beats on both bitrate and FLIP is left out). The last column reads the same comparison at the best foveal FLIP both the family and its codec without foveated encoding reach.\n\n| family | kbit/s at 60 fps | vs {TARGET} | vs the same codec without foveated encoding | the same at the best foveal FLIP both reach |\n|---|---:|---:|---:|---:|\n",
                t.flip_fovea, t.kbps
            ));
            let pct = |v: Option<f64>| v.map_or("–".into(), |v| format!("{:.1}%", 100.0 * v));
            let bound = |a: AtQuality| {
                if matches!(a, AtQuality::AtMost(_)) {
                    "≤ "
                } else {
                    ""
                }
            };
            for e in &self.equal_quality {
                let bytes = match e.at {
                    AtQuality::Interpolated(b) => format!("{b:.0}"),
                    AtQuality::AtMost(b) => format!("≤ {b:.0}"),
                    AtQuality::Unreached => "not reached".into(),
                };
                let best = e.at_strictest.map_or("–".into(), |p| match p.at {
                    AtQuality::Unreached => format!("not reached (FLIP {:.4})", p.flip_fovea),
                    a => format!("{}{} (FLIP {:.4})", bound(a), pct(p.vs_plain), p.flip_fovea),
                });
                s.push_str(&format!(
                    "| {} | {bytes} | {} | {}{} | {best} |\n",
                    e.family,
                    pct(e.vs_target),
                    if e.vs_plain.is_some() {
                        bound(e.at)
                    } else {
                        ""
                    },
                    pct(e.vs_plain)
                ));
            }
        }
        s
    }
}

/// Writes `codecs.json`, `codecs.md` and the bytes-vs-quality plot `codecs.svg`/`.png`.
pub fn write_codec_reports(report: &CodecReport, dir: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    let json = serde_json::to_string_pretty(report).map_err(std::io::Error::other)?;
    super::report::write_atomic(&dir.join("codecs.json"), json.as_bytes())?;
    super::report::write_atomic(&dir.join("codecs.md"), report.markdown().as_bytes())?;
    crate::plot::write(
        &crate::plot::codecs::CodecPlot::of(report),
        &dir.join("codecs"),
    )
    .map_err(std::io::Error::other)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_at_a_quality_interpolate_in_log_bytes_between_the_points_around_it() {
        let pts = [(4000.0, 0.02), (1000.0, 0.1), (2000.0, 0.05)];
        match at_quality(&pts, 0.075) {
            AtQuality::Interpolated(b) => assert!((b - 1000.0 * 2f64.sqrt()).abs() < 1e-6),
            other => panic!("{other:?}"),
        }
        // A measured point exactly at the target is its own bytes.
        let b = at_quality(&pts, 0.05).bytes().unwrap();
        assert!((b - 2000.0).abs() < 1e-6, "{b}");
    }

    #[test]
    fn bytes_at_a_quality_outside_the_curve_are_a_bound_or_unreached() {
        let pts = [(1000.0, 0.1), (2000.0, 0.05)];
        assert_eq!(at_quality(&pts, 0.2), AtQuality::AtMost(1000.0));
        assert_eq!(at_quality(&pts, 0.01), AtQuality::Unreached);
        assert_eq!(at_quality(&[], 0.1), AtQuality::Unreached);
        assert_eq!(
            at_quality(&[(f64::NAN, 0.0), (0.0, 0.0)], 0.1),
            AtQuality::Unreached
        );
    }

    #[test]
    fn a_curve_that_is_not_monotone_takes_its_first_crossing() {
        let pts = [
            (1000.0, 0.1),
            (2000.0, 0.04),
            (3000.0, 0.06),
            (4000.0, 0.01),
        ];
        let b = at_quality(&pts, 0.05).bytes().unwrap();
        assert!(b > 1000.0 && b < 2000.0, "{b}");
    }

    #[test]
    fn a_configuration_beaten_on_both_bitrate_and_quality_is_left_out() {
        // As on `gallery`: the lowest target costs more than the next and looks worse.
        let front = [(701.0, 0.0613), (967.0, 0.0608), (1494.0, 0.0596)];
        let with_worse = [(1048.0, 0.1021), front[0], front[1], front[2]];
        let (a, b) = (at_quality(&front, 0.0602), at_quality(&with_worse, 0.0602));
        assert_eq!(a, b);
        assert!(matches!(a, AtQuality::Interpolated(k) if k > 967.0 && k < 1494.0));
        // A cheaper point that looks worse stays: it is on the front.
        let cheap = [(300.0, 0.2), front[0], front[1], front[2]];
        assert_eq!(at_quality(&cheap, 0.0602), a);
        assert_eq!(at_quality(&cheap, 0.3), AtQuality::AtMost(300.0));
    }

    #[test]
    fn a_foveated_family_is_also_read_at_the_strictest_quality_both_reach() {
        let plain = [(700.0, 0.060), (1000.0, 0.059), (4000.0, 0.049)];
        // Cheaper everywhere, and better than the codec's best: read at the codec's 0.049,
        // between its own last two points.
        let foveated = [(400.0, 0.0595), (1500.0, 0.050), (2000.0, 0.047)];
        let p = strictest(&plain, &foveated).unwrap();
        assert_eq!(p.flip_fovea, 0.049);
        let b = p.at.bytes().unwrap();
        assert!(b > 1500.0 && b < 2000.0, "{b}");
        assert!((p.vs_plain.unwrap() - b / 4000.0).abs() < 1e-12);
        // A family that stops short of the codec's best is read at its own best, where the
        // codec's bitrate is interpolated.
        let short = [(400.0, 0.0595), (1500.0, 0.055)];
        let p = strictest(&plain, &short).unwrap();
        assert_eq!(
            (p.flip_fovea, p.at),
            (0.055, AtQuality::Interpolated(1500.0))
        );
        let own = at_quality(&plain, 0.055).bytes().unwrap();
        assert!(own > 1000.0 && own < 4000.0, "{own}");
        assert!((p.vs_plain.unwrap() - 1500.0 / own).abs() < 1e-12);
        assert_eq!(strictest(&[], &foveated), None);
    }
}
