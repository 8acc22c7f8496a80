//! EyeLink ASC files (what `edf2asc` writes): sample lines and the events around them.
//!
//! A sample line starts with its time in ms: `time x y pupil …` for one eye, `time xl yl pl
//! xr yr pr …` for two (velocity, resolution and flag columns may follow and are ignored), `.`
//! for a missing value and 0 for a missing pupil. `SAMPLES GAZE LEFT RIGHT …` says which eyes
//! the lines carry, `PUPIL AREA|DIAMETER` what the pupil is, `MSG t DISPLAY_COORDS l t r b`
//! (or `GAZE_COORDS`) the screen. `ESACC eye start end` labels saccades and `EBLINK eye start
//! end` marks blinks: samples inside a blink are track loss whatever the tracker wrote (the
//! positions around a blink are the lid, not the eye).

use super::types::{Eye, FormatError, ParseOptions, PupilUnit};
use super::{EyeSample, Raw, Row};
use crate::gaze::formats::Format;

/// Whether `text` reads as ASC: an `edf2asc` banner, or a START / SAMPLES line near the top.
pub fn looks_like(text: &str) -> bool {
    text.lines().take(500).any(|l| {
        let first = l.split_whitespace().next().unwrap_or("");
        l.starts_with("** CONVERTED FROM") || first == "START" || first == "SAMPLES"
    })
}

fn eye_index(token: &str) -> Option<usize> {
    match token {
        "L" => Some(0),
        "R" => Some(1),
        _ => None,
    }
}

/// `EVENT eye start end …` → (eye, start, end).
fn span(tokens: &[&str]) -> Option<(usize, f64, f64)> {
    let eye = eye_index(tokens.get(1)?)?;
    let a: f64 = tokens.get(2)?.parse().ok()?;
    let b: f64 = tokens.get(3)?.parse().ok()?;
    (a.is_finite() && b.is_finite() && a <= b).then_some((eye, a, b))
}

fn coords(tokens: &[&str]) -> Option<(u32, u32)> {
    let at = tokens
        .iter()
        .position(|t| *t == "DISPLAY_COORDS" || *t == "GAZE_COORDS")?;
    let n: Vec<f64> = tokens[at + 1..]
        .iter()
        .take(4)
        .map(|t| t.parse::<f64>())
        .collect::<Result<_, _>>()
        .ok()?;
    let (w, h) = (n.get(2)? - n.first()? + 1.0, n.get(3)? - n.get(1)? + 1.0);
    (w >= 1.0 && h >= 1.0 && w <= 65_536.0 && h <= 65_536.0).then_some((w as u32, h as u32))
}

pub fn read(text: &str, opts: &ParseOptions) -> Result<Raw, FormatError> {
    if text.trim().is_empty() {
        return Err(FormatError::Empty);
    }
    let mut eyes_in_lines = [true, false];
    let mut seen_eyes = [false, false];
    let mut pupil_unit = PupilUnit::Area;
    let mut screen = None;
    let mut saccades: [Vec<(f64, f64)>; 2] = Default::default();
    let mut blinks: [Vec<(f64, f64)>; 2] = Default::default();
    let mut rows = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line_no = i + 1;
        let tokens: Vec<&str> = line.split_whitespace().collect();
        let Some(&first) = tokens.first() else {
            continue;
        };
        if first.as_bytes()[0].is_ascii_digit() {
            rows.push(sample(&tokens, eyes_in_lines, line_no)?);
            continue;
        }
        match first {
            "SAMPLES" => {
                let left = tokens.contains(&"LEFT");
                let right = tokens.contains(&"RIGHT");
                eyes_in_lines = if left || right {
                    [left, right]
                } else {
                    [true, false]
                };
                seen_eyes[0] |= eyes_in_lines[0];
                seen_eyes[1] |= eyes_in_lines[1];
            }
            "PUPIL" if tokens.contains(&"DIAMETER") => pupil_unit = PupilUnit::Diameter,
            "MSG" if screen.is_none() => screen = coords(&tokens),
            "ESACC" => saccades_push(&mut saccades, &tokens),
            "EBLINK" => saccades_push(&mut blinks, &tokens),
            _ => {}
        }
    }
    if rows.is_empty() {
        return Err(FormatError::NoSamples);
    }
    if !seen_eyes.iter().any(|s| *s) {
        seen_eyes = [true, false];
    }
    for (eye, spans) in blinks.iter().enumerate() {
        mark_blinks(&mut rows, eye, spans);
    }
    let (w, h) = match (opts.screen, screen) {
        (Some((w, h)), _) | (None, Some((w, h))) => (f64::from(w), f64::from(h)),
        (None, None) => return Err(FormatError::NeedsScreen(Format::EyelinkAsc)),
    };
    for row in &mut rows {
        for e in &mut row.eyes {
            e.xy = e.xy.map(|[x, y]| [x / w, y / h]);
        }
    }
    let wanted: Vec<usize> = match opts.eye {
        Some(Eye::Left) => vec![0],
        Some(Eye::Right) => vec![1],
        _ => vec![0, 1],
    };
    let mut labels: Vec<(f64, f64)> = wanted.iter().flat_map(|&e| saccades[e].clone()).collect();
    labels.sort_by(|a, b| a.0.total_cmp(&b.0));
    let labelled = saccades.iter().any(|s| !s.is_empty());
    Ok(Raw {
        format: Format::EyelinkAsc,
        rows,
        eyes: seen_eyes,
        pupil_unit: Some(pupil_unit),
        saccades: labelled.then_some(labels),
        screen: screen.filter(|_| opts.screen.is_none()),
    })
}

fn saccades_push(into: &mut [Vec<(f64, f64)>; 2], tokens: &[&str]) {
    if let Some((eye, a, b)) = span(tokens) {
        into[eye].push((a, b));
    }
}

/// Samples inside a blink of `eye` lose that eye's position and pupil.
fn mark_blinks(rows: &mut [Row], eye: usize, spans: &[(f64, f64)]) {
    for &(a, b) in spans {
        let start = rows.partition_point(|r| r.t_ms < a);
        for row in rows[start..].iter_mut().take_while(|r| r.t_ms <= b) {
            row.eyes[eye] = EyeSample::default();
        }
    }
}

fn sample(tokens: &[&str], eyes: [bool; 2], line: usize) -> Result<Row, FormatError> {
    let number = |k: usize, column: &str| -> Result<Option<f64>, FormatError> {
        let v = tokens.get(k).copied().unwrap_or(".");
        if v == "." {
            return Ok(None);
        }
        v.parse::<f64>()
            .map(|n| n.is_finite().then_some(n))
            .map_err(|_| FormatError::NotNumeric {
                line,
                column: column.to_string(),
                value: v.to_string(),
            })
    };
    let Some(t) = number(0, "time")? else {
        return Err(FormatError::Malformed {
            line,
            what: "a sample line without a time".into(),
        });
    };
    let mut row = Row {
        line,
        t_ms: t,
        eyes: [EyeSample::default(); 2],
    };
    let mut k = 1;
    for (e, present) in eyes.into_iter().enumerate() {
        if !present {
            continue;
        }
        let (x, y, p) = (
            number(k, "x")?,
            number(k + 1, "y")?,
            number(k + 2, "pupil")?,
        );
        row.eyes[e] = EyeSample {
            xy: x.zip(y).map(|(x, y)| [x, y]),
            pupil: p.filter(|p| *p > 0.0),
        };
        k += 3;
    }
    Ok(row)
}
