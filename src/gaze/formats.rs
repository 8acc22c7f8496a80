//! Gaze recording formats: EyeLink ASC and Data Viewer sample reports, the EyeLink CSV layout
//! of `../shared/data/gaze`, Pupil Labs Core `gaze_positions.csv` and Neon `gaze.csv`, Tobii
//! Pro Lab exports and an SDK-style Tobii CSV, and a generic CSV with column mapping.
//! Auto-detected from the header (or, for ASC, from its START/SAMPLES lines) where
//! unambiguous; binocular files give the left, right or average eye (`--eye`).

mod asc;
mod table;
#[cfg(test)]
mod tests;
mod types;

pub use table::detect;
pub use types::{
    Columns, Eye, Format, FormatError, ParseOptions, PupilUnit, Recording, MAX_SPAN_DAYS,
};

use super::Sample;

/// One eye at one row, before an eye is chosen: position as a fraction of the screen, pupil
/// in the file's own unit.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct EyeSample {
    xy: Option<[f64; 2]>,
    pupil: Option<f64>,
}

/// One row of a file: its line, time in ms on the file's clock, left and right eye (a
/// monocular format of unknown eye uses the first).
#[derive(Debug, Clone, Copy)]
struct Row {
    line: usize,
    t_ms: f64,
    eyes: [EyeSample; 2],
}

/// What a reader found, before the eye, time and pupil rules are applied.
struct Raw {
    format: Format,
    rows: Vec<Row>,
    /// Which eyes the file has columns or samples for.
    eyes: [bool; 2],
    /// The pupil column's unit, where the format says.
    pupil_unit: Option<PupilUnit>,
    /// Saccade intervals on the file's clock, where the file labels them.
    saccades: Option<Vec<(f64, f64)>>,
    screen: Option<(u32, u32)>,
}

pub fn parse(text: &str, opts: &ParseOptions) -> Result<Recording, FormatError> {
    let asc = match opts.format {
        Some(f) => f == Format::EyelinkAsc,
        None => asc::looks_like(text),
    };
    let raw = if asc {
        asc::read(text, opts)?
    } else {
        table::read(text, opts)?
    };
    finish(raw, opts)
}

/// The eye to use: the one asked for (an error if the file lacks it), else the average of a
/// binocular file, else the only eye. A binocular file whose data has only one eye (a
/// monocular Data Viewer report keeps both eyes' columns) counts as that eye's.
fn choose_eye(raw: &Raw, asked: Option<Eye>) -> Result<Option<Eye>, FormatError> {
    let has_data = |e: usize| raw.eyes[e] && raw.rows.iter().any(|r| r.eyes[e].xy.is_some());
    let (left, right) = (has_data(0), has_data(1));
    let binocular = raw.eyes[0] && raw.eyes[1];
    match asked {
        None if binocular && left && right => Ok(Some(Eye::Average)),
        None if binocular && right => Ok(Some(Eye::Right)),
        None if binocular => Ok(Some(Eye::Left)),
        None => Ok(None),
        Some(Eye::Right) if !raw.eyes[1] || (binocular && !right && left) => {
            Err(FormatError::EyeMissing {
                asked: Eye::Right,
                has: "left",
            })
        }
        Some(Eye::Left) if raw.eyes[1] && !raw.eyes[0] || (binocular && !left && right) => {
            Err(FormatError::EyeMissing {
                asked: Eye::Left,
                has: "right",
            })
        }
        Some(e) => Ok(Some(e)),
    }
}

fn pick(row: &Row, eye: Option<Eye>, only: usize) -> EyeSample {
    let [l, r] = row.eyes;
    match eye {
        None => row.eyes[only],
        Some(Eye::Left) => l,
        Some(Eye::Right) => r,
        Some(Eye::Average) => {
            let xy = match (l.xy, r.xy) {
                (Some(a), Some(b)) => Some([(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0]),
                (a, b) => a.or(b),
            };
            let pupil = match (l.pupil, r.pupil) {
                (Some(a), Some(b)) => Some((a + b) / 2.0),
                (a, b) => a.or(b),
            };
            EyeSample { xy, pupil }
        }
    }
}

fn finish(raw: Raw, opts: &ParseOptions) -> Result<Recording, FormatError> {
    let eye = choose_eye(&raw, opts.eye)?;
    let only = usize::from(!raw.eyes[0] && raw.eyes[1]);
    let mut samples = Vec::with_capacity(raw.rows.len());
    let mut raw_pupil = Vec::with_capacity(raw.rows.len());
    let mut previous = f64::NEG_INFINITY;
    let start = raw.rows.first().map_or(0.0, |r| r.t_ms);
    for row in &raw.rows {
        let t = row.t_ms;
        if t < previous {
            return Err(FormatError::Unsorted {
                line: row.line,
                t,
                previous,
            });
        }
        if t == previous {
            return Err(FormatError::Duplicate { line: row.line, t });
        }
        previous = t;
        let days = (t - start) / 86_400_000.0;
        if !(days <= types::MAX_SPAN_DAYS) {
            return Err(FormatError::TooLong {
                line: row.line,
                t: t - start,
                days,
            });
        }
        let e = pick(row, eye, only);
        raw_pupil.push(e.pupil);
        samples.push(Sample {
            t_ms: t - start,
            xy: e.xy,
            pupil_mm: None,
        });
    }
    if samples.is_empty() {
        return Err(FormatError::NoSamples);
    }
    let unit = opts.pupil_unit.or(raw.pupil_unit).unwrap_or(PupilUnit::Mm);
    let pupil_rule = pupil_rule(&mut samples, &raw_pupil, unit, opts.pupil_median_mm);
    Ok(Recording {
        format: raw.format,
        samples,
        pupil_rule,
        eye,
        screen: raw.screen,
        saccades: raw
            .saccades
            .map(|v| v.into_iter().map(|(a, b)| (a - start, b - start)).collect()),
    })
}

/// Turns the file's pupil values into millimetres, and says how.
fn pupil_rule(
    samples: &mut [Sample],
    raw: &[Option<f64>],
    unit: PupilUnit,
    median_mm: f64,
) -> Option<String> {
    if raw.iter().all(Option::is_none) {
        return None;
    }
    if unit == PupilUnit::Mm {
        for (s, p) in samples.iter_mut().zip(raw) {
            s.pupil_mm = p.map(|d| d.clamp(1.0, 10.0));
        }
        return Some("pupil diameter in mm as recorded, clamped to 1–10 mm".into());
    }
    // Arbitrary units: diameter ∝ value (or ∝ √area); the recording's median maps to the
    // stated diameter.
    let to_diameter = |v: f64| if unit == PupilUnit::Area { v.sqrt() } else { v };
    // The median of the values as recorded (√ keeps the order, so it is also the diameters'
    // median): squaring √area back printed 1103 as "1102.9999999999998".
    let mut values: Vec<f64> = raw.iter().flatten().copied().collect();
    values.sort_by(|a, b| a.total_cmp(b));
    let median = values[values.len() / 2];
    let k = median_mm / to_diameter(median);
    for (s, p) in samples.iter_mut().zip(raw) {
        s.pupil_mm = p.map(|v| (k * to_diameter(v)).clamp(1.0, 10.0));
    }
    Some(match unit {
        PupilUnit::Area => format!(
            "pupil area → diameter: mm = {k:.5}·√area (median area {median} ↦ {median_mm} mm), clamped to 1–10 mm"
        ),
        _ => format!(
            "pupil diameter in arbitrary units: mm = {k:.5}·value (median {median} ↦ {median_mm} mm), clamped to 1–10 mm"
        ),
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
