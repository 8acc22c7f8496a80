//! Gaze recording formats: EyeLink CSV (as in `../shared/data/gaze`), Pupil Labs Core
//! `gaze_positions.csv`, Pupil Labs Neon `gaze.csv`, a Tobii-style export, and a generic CSV with
//! column mapping. Auto-detected from the header where unambiguous.

use std::collections::HashMap;

mod types;

pub use types::{Columns, Format, FormatError, ParseOptions, Recording, MAX_SPAN_DAYS};

use super::Sample;

pub fn detect(header: &[&str]) -> Option<Format> {
    let has = |c: &str| header.iter().any(|h| *h == c);
    if has("t_s") && has("xpos") && has("ypos") {
        Some(Format::Eyelink)
    } else if has("norm_pos_x") && has("norm_pos_y") && has("gaze_timestamp") {
        Some(Format::PupilCore)
    } else if has("timestamp [ns]") && has("gaze x [px]") {
        Some(Format::PupilNeon)
    } else if has("device_time_stamp") && has("gaze_point_x") {
        Some(Format::Tobii)
    } else if has("t_ms") && has("x") && has("y") {
        Some(Format::Generic)
    } else {
        None
    }
}

pub fn parse(text: &str, opts: &ParseOptions) -> Result<Recording, FormatError> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let (_, header_line) = lines.next().ok_or(FormatError::Empty)?;
    let header: Vec<&str> = header_line
        .split(',')
        .map(|h| h.trim().trim_matches('"'))
        .collect();
    let format = match opts.format {
        Some(f) => f,
        None => detect(&header).ok_or_else(|| FormatError::Unknown {
            header: header_line.to_string(),
        })?,
    };
    let index: HashMap<&str, usize> = header.iter().enumerate().map(|(i, h)| (*h, i)).collect();
    let col = |name: &str| {
        index
            .get(name)
            .copied()
            .ok_or_else(|| FormatError::MissingColumn {
                format,
                column: name.to_string(),
                header: header_line.to_string(),
            })
    };
    // (time column, scale to ms, x, y, pupil, x/y scale, flip y, confidence)
    let c = &opts.columns;
    let (t_col, t_scale, x_col, y_col, pupil_col, conf_col) = match format {
        Format::Eyelink => (
            col("t_s")?,
            1e3,
            col("xpos")?,
            col("ypos")?,
            index.get("ps").copied(),
            None,
        ),
        Format::PupilCore => (
            col("gaze_timestamp")?,
            1e3,
            col("norm_pos_x")?,
            col("norm_pos_y")?,
            None,
            index.get("confidence").copied(),
        ),
        Format::PupilNeon => (
            col("timestamp [ns]")?,
            1e-6,
            col("gaze x [px]")?,
            col("gaze y [px]")?,
            None,
            None,
        ),
        Format::Tobii => (
            col("device_time_stamp")?,
            1e-3,
            col("gaze_point_x")?,
            col("gaze_point_y")?,
            index.get("pupil_diameter").copied(),
            None,
        ),
        Format::Generic => {
            let scale = match c.time_unit.as_str() {
                "s" => 1e3,
                "ms" => 1.0,
                "us" => 1e-3,
                "ns" => 1e-6,
                other => return Err(FormatError::TimeUnit(other.to_string())),
            };
            let pupil = match &c.pupil {
                Some(p) => index.get(p.as_str()).copied(),
                None => None,
            };
            (col(&c.time)?, scale, col(&c.x)?, col(&c.y)?, pupil, None)
        }
    };
    let pixels = match format {
        Format::Eyelink => true,
        Format::PupilNeon => true,
        Format::Generic => c.pixels,
        _ => false,
    };
    let screen = match (pixels, opts.screen, format) {
        (false, _, _) => (1.0, 1.0),
        (true, Some((w, h)), _) => (f64::from(w), f64::from(h)),
        (true, None, Format::PupilNeon) => (1600.0, 1200.0),
        (true, None, f) => return Err(FormatError::NeedsScreen(f)),
    };
    let names = &header;
    let mut samples = Vec::new();
    let mut raw_pupil = Vec::new();
    let mut t0: Option<f64> = None;
    let mut previous = f64::NEG_INFINITY;
    for (i, line) in lines {
        let line_no = i + 1;
        let fields: Vec<&str> = line
            .split(',')
            .map(|f| f.trim().trim_matches('"'))
            .collect();
        let number = |k: usize| -> Result<Option<f64>, FormatError> {
            let v = fields.get(k).copied().unwrap_or("");
            if v.is_empty() || v.eq_ignore_ascii_case("nan") {
                return Ok(None);
            }
            // inf and -nan parse as floats; a value that is not finite is no value.
            v.parse::<f64>()
                .map(|n| n.is_finite().then_some(n))
                .map_err(|_| FormatError::NotNumeric {
                    line: line_no,
                    column: names.get(k).copied().unwrap_or("?").to_string(),
                    value: v.to_string(),
                })
        };
        let Some(t_raw) = number(t_col)? else {
            return Err(FormatError::NotNumeric {
                line: line_no,
                column: names[t_col].to_string(),
                value: fields.get(t_col).copied().unwrap_or("").to_string(),
            });
        };
        let t = t_raw * t_scale;
        if t < previous {
            return Err(FormatError::Unsorted {
                line: line_no,
                t,
                previous,
            });
        }
        if t == previous {
            return Err(FormatError::Duplicate { line: line_no, t });
        }
        previous = t;
        let start = *t0.get_or_insert(t);
        let days = (t - start) / 86_400_000.0;
        if !(days <= types::MAX_SPAN_DAYS) {
            return Err(FormatError::TooLong {
                line: line_no,
                t: t - start,
                days,
            });
        }
        let (x, y) = (number(x_col)?, number(y_col)?);
        let confident = match conf_col {
            Some(k) => number(k)?.is_some_and(|c| c >= opts.min_confidence),
            None => true,
        };
        let xy = match (x, y, confident) {
            (Some(x), Some(y), true) => {
                let (nx, ny) = (x / screen.0, y / screen.1);
                Some(if format == Format::PupilCore {
                    [nx, 1.0 - ny]
                } else {
                    [nx, ny]
                })
            }
            _ => None,
        };
        let pupil = match pupil_col {
            Some(k) => number(k)?.filter(|p| *p > 0.0),
            None => None,
        };
        raw_pupil.push(pupil);
        samples.push(Sample {
            t_ms: t - start,
            xy,
            pupil_mm: None,
        });
    }
    if samples.is_empty() {
        return Err(FormatError::NoSamples);
    }
    let pupil_rule = match format {
        Format::Eyelink => {
            // EyeLink reports pupil AREA in arbitrary units: diameter ∝ √area. Scale so the
            // recording's median pupil is `pupil_median_mm`.
            let mut areas: Vec<f64> = raw_pupil.iter().flatten().copied().collect();
            areas.sort_by(|a, b| a.total_cmp(b));
            areas.get(areas.len() / 2).copied().map(|median| {
                let k = opts.pupil_median_mm / median.sqrt();
                for (s, p) in samples.iter_mut().zip(&raw_pupil) {
                    s.pupil_mm = p.map(|a| (k * a.sqrt()).clamp(1.0, 10.0));
                }
                format!("pupil area → diameter: mm = {k:.5}·√area (median area {median} ↦ {} mm), clamped to 1–10 mm", opts.pupil_median_mm)
            })
        }
        _ => {
            for (s, p) in samples.iter_mut().zip(&raw_pupil) {
                s.pupil_mm = p.map(|d| d.clamp(1.0, 10.0));
            }
            raw_pupil
                .iter()
                .any(|p| p.is_some())
                .then(|| "pupil diameter in mm as recorded, clamped to 1–10 mm".to_string())
        }
    };
    Ok(Recording {
        format,
        samples,
        pupil_rule,
        saccades: None,
    })
}

/// Writes samples in the generic format (what session recording produces).
pub fn write_generic(samples: &[Sample]) -> String {
    let mut out = String::from("t_ms,x,y,pupil_mm\n");
    for s in samples {
        let (x, y) =
            s.xy.map(|[x, y]| (format!("{x}"), format!("{y}")))
                .unwrap_or_default();
        let p = s.pupil_mm.map(|p| format!("{p}")).unwrap_or_default();
        out.push_str(&format!("{},{x},{y},{p}\n", s.t_ms));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_values_are_refused_or_missing_never_used() {
        let generic = |text: &str| {
            let opts = ParseOptions {
                format: Some(Format::Generic),
                ..ParseOptions::default()
            };
            parse(text, &opts)
        };
        let head = "t_ms,x,y\n";
        for bad_time in ["inf", "-inf", "nan", "-nan", "1e400"] {
            let text = format!("{head}0,0.5,0.5\n{bad_time},0.5,0.5\n");
            assert!(generic(&text).is_err(), "time {bad_time}");
        }
        let far = generic(&format!("{head}0,0.5,0.5\n1e300,0.5,0.5\n"));
        assert!(
            matches!(far, Err(FormatError::TooLong { line: 3, .. })),
            "{far:?}"
        );
        let rec = generic(&format!("{head}0,-nan,0.5\n1,0.5,inf\n2,0.5,0.5\n")).unwrap();
        let xy: Vec<_> = rec.samples.iter().map(|s| s.xy).collect();
        assert_eq!(xy, [None, None, Some([0.5, 0.5])]);
    }

    fn eyelink() -> ParseOptions {
        ParseOptions {
            screen: Some((1920, 1200)),
            ..Default::default()
        }
    }

    /// The first 1.2 s of the real 500 Hz EyeLink recording cut around a blink (from 2.012 s).
    const EXCERPT: &str = "t_s,xpos,ypos,ps\n0.000,952.8,593.5,1068.0\n0.002,952.6,593.6,1068.0\n2.002,1092.1,564.8,1072.0\n2.012,,,0.0\n2.014,,,0.0\n2.100,2400.0,-30.0,1000.0\n";

    #[test]
    fn eyelink_excerpt_with_a_blink_and_an_off_screen_sample() {
        let r = parse(EXCERPT, &eyelink()).unwrap();
        assert_eq!(r.format, Format::Eyelink);
        assert_eq!(r.samples.len(), 6);
        assert_eq!(r.samples[0].t_ms, 0.0);
        assert!((r.samples[2].t_ms - 2002.0).abs() < 1e-9);
        let [x, y] = r.samples[0].xy.unwrap();
        assert!((x - 952.8 / 1920.0).abs() < 1e-12 && (y - 593.5 / 1200.0).abs() < 1e-12);
        assert_eq!(r.samples[3].xy, None, "track loss");
        assert_eq!(r.samples[3].pupil_mm, None, "blink: pupil 0");
        assert!(
            super::super::sendable(&r.samples[5]).is_none(),
            "far off screen: not sent"
        );
        // Median area 1068 maps to 4 mm.
        assert!((r.samples[0].pupil_mm.unwrap() - 4.0).abs() < 1e-9);
        assert!(r.pupil_rule.unwrap().contains("√area"));
    }

    #[test]
    fn the_shipped_recordings_parse() {
        for (file, w, h, n) in [(
            "../../assets/gaze/eyelink_500hz_1920x1200.csv",
            1920,
            1200,
            14_353,
        )] {
            let text = std::fs::read_to_string(
                std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                    .join("src/gaze")
                    .join(file),
            )
            .unwrap();
            let r = parse(
                &text,
                &ParseOptions {
                    screen: Some((w, h)),
                    ..Default::default()
                },
            )
            .unwrap();
            assert_eq!(r.samples.len(), n);
            let lost = r.samples.iter().filter(|s| s.xy.is_none()).count();
            assert!(lost > 0 && lost < n / 5, "track loss {lost}");
        }
    }

    #[test]
    fn other_formats_are_detected_and_normalised() {
        let core = "gaze_timestamp,world_index,confidence,norm_pos_x,norm_pos_y\n100.0,0,0.9,0.25,0.75\n100.01,1,0.3,0.5,0.5\n";
        let r = parse(core, &ParseOptions::default()).unwrap();
        assert_eq!(r.format, Format::PupilCore);
        assert_eq!(
            r.samples[0].xy,
            Some([0.25, 0.25]),
            "bottom-left origin flipped"
        );
        assert_eq!(r.samples[1].xy, None, "low confidence is track loss");
        assert!((r.samples[1].t_ms - 10.0).abs() < 1e-6);
        let neon = "section id,recording id,timestamp [ns],gaze x [px],gaze y [px],worn\na,b,1000000000,800,600,1\na,b,1005000000,0,0,1\n";
        let r = parse(neon, &ParseOptions::default()).unwrap();
        assert_eq!(
            (r.format, r.samples[0].xy, r.samples[1].t_ms),
            (Format::PupilNeon, Some([0.5, 0.5]), 5.0)
        );
        let tobii = "device_time_stamp,gaze_point_x,gaze_point_y,pupil_diameter\n1000,0.1,0.2,3.5\n9333,0.3,0.4,-1\n";
        let r = parse(tobii, &ParseOptions::default()).unwrap();
        assert_eq!(
            (r.format, r.samples[0].pupil_mm, r.samples[1].pupil_mm),
            (Format::Tobii, Some(3.5), None)
        );
        let generic = "time,gx,gy\n0,10,20\n1,30,40\n";
        let opts = ParseOptions {
            format: Some(Format::Generic),
            screen: Some((100, 100)),
            columns: Columns {
                time: "time".into(),
                x: "gx".into(),
                y: "gy".into(),
                pupil: None,
                time_unit: "s".into(),
                pixels: true,
            },
            ..Default::default()
        };
        let r = parse(generic, &opts).unwrap();
        assert_eq!(
            (r.samples[1].t_ms, r.samples[1].xy),
            (1000.0, Some([0.3, 0.4]))
        );
    }

    #[test]
    fn malformed_files_get_clear_errors() {
        assert_eq!(parse("", &eyelink()), Err(FormatError::Empty));
        assert_eq!(
            parse("t_s,xpos,ypos,ps\n", &eyelink()),
            Err(FormatError::NoSamples)
        );
        assert!(matches!(
            parse("a,b\n1,2\n", &eyelink()),
            Err(FormatError::Unknown { .. })
        ));
        let e = parse("t_s,xpos,ypos,ps\n0.0,abc,1,1\n", &eyelink()).unwrap_err();
        assert_eq!(
            e,
            FormatError::NotNumeric {
                line: 2,
                column: "xpos".into(),
                value: "abc".into()
            }
        );
        assert!(matches!(
            parse("t_s,xpos,ypos,ps\n0.2,1,1,1\n0.1,1,1,1\n", &eyelink()),
            Err(FormatError::Unsorted { line: 3, .. })
        ));
        assert!(matches!(
            parse("t_s,xpos,ypos,ps\n0.2,1,1,1\n0.2,1,1,1\n", &eyelink()),
            Err(FormatError::Duplicate { line: 3, .. })
        ));
        assert_eq!(
            parse("t_s,xpos,ypos,ps\n0,1,1,1\n", &ParseOptions::default()),
            Err(FormatError::NeedsScreen(Format::Eyelink))
        );
        let missing = ParseOptions {
            format: Some(Format::Tobii),
            ..Default::default()
        };
        assert!(parse("device_time_stamp,x\n1,2\n", &missing)
            .unwrap_err()
            .to_string()
            .contains("gaze_point_x"));
    }

    #[test]
    fn generic_csv_round_trips() {
        let samples = vec![
            Sample {
                t_ms: 0.0,
                xy: Some([0.25, 0.5]),
                pupil_mm: Some(3.5),
            },
            Sample {
                t_ms: 2.5,
                xy: None,
                pupil_mm: None,
            },
            Sample {
                t_ms: 4.0,
                xy: Some([1.0, 0.0]),
                pupil_mm: None,
            },
        ];
        let back = parse(&write_generic(&samples), &ParseOptions::default()).unwrap();
        assert_eq!(back.samples, samples);
    }
}
