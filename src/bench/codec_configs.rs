//! The encoder configurations `fovea bench --sweep codecs` compares, and the families (codec
//! and foveated encoding) whose curves the report reads equal quality off.

use serde::{Deserialize, Serialize};

use crate::encode::foveated::LowPass;
use crate::protocol::Codec;

/// How each frame is encoded.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CodecConfig {
    pub name: String,
    pub codec: Codec,
    /// JPEG quality (JPEG configurations).
    pub jpeg_q: u8,
    /// Target bitrate (H.264 configurations).
    pub h264_kbps: Option<u32>,
    /// The eccentricity-matched low-pass before encoding.
    pub low_pass: bool,
    /// A downscaled frame plus a foveal inset this many degrees wide (with H.264 both packed
    /// into one picture).
    pub inset_deg: Option<f64>,
    /// The periphery's macroblocks held while they change by less than the eye can tell
    /// there (`encode::hold`; H.264, whole frames).
    #[serde(default)]
    pub hold: bool,
}

impl CodecConfig {
    /// The curve a configuration belongs to: the same codec and foveated encoding, varying only
    /// in quality or bitrate.
    pub fn family(&self) -> String {
        match self.foveated() {
            Some(how) => format!("{} + {how}", self.codec_name()),
            None => self.codec_name().to_string(),
        }
    }

    /// The family of the same codec without foveated encoding.
    pub fn plain_family(&self) -> String {
        self.codec_name().to_string()
    }

    fn codec_name(&self) -> &'static str {
        match self.codec {
            Codec::H264 => "H.264",
            Codec::Png => "PNG",
            Codec::Jpeg => "JPEG",
        }
    }

    /// The foveated encoding, if any, as the family names it.
    fn foveated(&self) -> Option<String> {
        // 20° and 16° print whole; the derived 13.3° to a tenth.
        let inset = |deg: f64| match deg.fract().abs() < 1e-9 {
            true => format!("inset {deg:.0}°"),
            false => format!("inset {deg:.1}°"),
        };
        let spatial = match (self.low_pass, self.inset_deg) {
            (false, Some(deg)) => Some(inset(deg)),
            (true, Some(deg)) => Some(format!("{} + low-pass", inset(deg))),
            (true, None) => Some("low-pass".into()),
            (false, None) => None,
        };
        match (spatial, self.hold) {
            (Some(s), true) => Some(format!("{s} + hold")),
            (None, true) => Some("hold".into()),
            (s, false) => s,
        }
    }
}

/// H.264 targets, kbit/s, from 125: with 500 the lowest, every H.264 row of `bunny-marble` lay
/// below JPEG q85's foveal FLIP and its read-offs were only bounds (with 250, two still were).
const H264_KBPS: [u32; 7] = [125, 250, 500, 1000, 2000, 4000, 8000];

/// JPEG q50–95 and H.264 at 125–8000 kbit/s, each plain and low-passed, and both with a 20°
/// and a 16° inset, H.264 with the 16° inset low-passed too, and JPEG with a 13.3° inset: the
/// encoder comparison issue 16 asks for.
pub fn codec_configs() -> Vec<CodecConfig> {
    let mut out = Vec::new();
    let jpeg = |q: u8, low_pass: bool, inset_deg: Option<f64>| CodecConfig {
        name: String::new(),
        codec: Codec::Jpeg,
        jpeg_q: q,
        h264_kbps: None,
        low_pass,
        inset_deg,
        hold: false,
    };
    for low in [false, true] {
        for q in [50u8, 75, 85, 95] {
            out.push(jpeg(q, low, None));
        }
        for kbps in H264_KBPS {
            out.push(CodecConfig {
                h264_kbps: Some(kbps),
                codec: Codec::H264,
                ..jpeg(0, low, None)
            });
        }
    }
    // The page's 20°, and the narrowest inset whose core holds the 5° judged fovea wherever a
    // video inset is held (16°: `inset_packed::narrowest_deg`).
    let narrowest = crate::encode::inset_packed::narrowest_deg(LowPass::default().guard_deg);
    for deg in [20.0, narrowest] {
        for q in [50u8, 75, 85, 95] {
            out.push(jpeg(q, false, Some(deg)));
        }
        for kbps in H264_KBPS {
            out.push(CodecConfig {
                h264_kbps: Some(kbps),
                codec: Codec::H264,
                ..jpeg(0, false, Some(deg))
            });
        }
    }
    // Both at once: the inset's downscaled whole frame low-passed further out, where the eye
    // resolves less than its halved resolution. H.264 only: JPEG's insets meet the goal alone.
    for kbps in H264_KBPS {
        out.push(CodecConfig {
            h264_kbps: Some(kbps),
            codec: Codec::H264,
            ..jpeg(0, true, Some(narrowest))
        });
    }
    // The periphery held in time (`encode::hold`): alone, after the low-pass, and with the
    // inset and the low-pass.
    for (low_pass, inset) in [(false, None), (true, None), (true, Some(narrowest))] {
        for kbps in H264_KBPS {
            out.push(CodecConfig {
                h264_kbps: Some(kbps),
                codec: Codec::H264,
                hold: true,
                ..jpeg(0, low_pass, inset)
            });
        }
    }
    // A still image's inset is placed on the gaze every frame, with no hold to allow for:
    // its narrowest is 13.3° (`inset::narrowest_deg`). JPEG only (a video inset is held).
    let still = crate::encode::inset::narrowest_deg(LowPass::default().guard_deg);
    for q in [50u8, 75, 85, 95] {
        out.push(jpeg(q, false, Some(still)));
    }
    for c in &mut out {
        let knob = match c.h264_kbps {
            Some(k) => format!("{k} kbit/s"),
            None => format!("q{}", c.jpeg_q),
        };
        c.name = match c.foveated() {
            Some(how) => format!("{} {knob} + {how}", c.codec_name()),
            None => format!("{} {knob}", c.codec_name()),
        };
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_family_has_configurations_named_after_it() {
        let configs = codec_configs();
        let names: Vec<&str> = configs.iter().map(|c| c.name.as_str()).collect();
        for n in [
            "JPEG q85",
            "H.264 4000 kbit/s",
            "JPEG q85 + low-pass",
            "H.264 500 kbit/s + low-pass",
            "JPEG q85 + inset 20°",
            "H.264 1000 kbit/s + inset 20°",
        ] {
            assert!(names.contains(&n), "{n} in {names:?}");
        }
        assert_eq!(names.iter().filter(|n| n.contains("inset 20°")).count(), 11);
        assert_eq!(names.iter().filter(|n| n.contains("inset 16°")).count(), 25);
        // Inset and low-pass together are a family of their own, H.264 only.
        let both: Vec<_> = configs
            .iter()
            .filter(|c| c.low_pass && c.inset_deg.is_some() && !c.hold)
            .collect();
        assert_eq!(both.len(), 7);
        assert!(both
            .iter()
            .all(|c| c.codec == Codec::H264 && c.family() == "H.264 + inset 16° + low-pass"));
        // The held periphery: three families of H.264, each named after all it does.
        let held: Vec<_> = configs.iter().filter(|c| c.hold).collect();
        assert_eq!(held.len(), 21);
        assert!(held.iter().all(|c| c.codec == Codec::H264));
        for n in [
            "H.264 1000 kbit/s + hold",
            "H.264 1000 kbit/s + low-pass + hold",
            "H.264 1000 kbit/s + inset 16° + low-pass + hold",
        ] {
            assert!(names.contains(&n), "{n} in {names:?}");
        }
        // The still inset's derived width, JPEG only.
        assert!(names.contains(&"JPEG q85 + inset 13.3°"), "{names:?}");
        assert_eq!(
            names.iter().filter(|n| n.contains("inset 13.3°")).count(),
            4
        );
    }
}
