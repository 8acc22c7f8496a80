//! Delimited exports (CSV, TSV, semicolons; decimal points or commas), read with the `csv`
//! crate: every format except ASC. The delimiter is the header's most frequent of tab,
//! semicolon and comma; decimal commas are assumed when the delimiter is not a comma and a
//! data field in the first rows looks like `12,5`.

use super::types::{Format, FormatError, ParseOptions, PupilUnit};
use super::{EyeSample, Raw, Row};

pub fn detect(header: &[&str]) -> Option<Format> {
    let has = |c: &str| header.contains(&c);
    let has_prefix = |c: &str| header.iter().any(|h| h.starts_with(c));
    if has("t_s")
        && ((has("xpos") && has("ypos"))
            || has("xpos_l")
            || has("xpos_left")
            || has("xpos_r")
            || has("xpos_right"))
    {
        Some(Format::Eyelink)
    } else if has("TIMESTAMP") && (has("LEFT_GAZE_X") || has("RIGHT_GAZE_X")) {
        Some(Format::DataViewer)
    } else if has_prefix("Recording timestamp") && (has("Gaze point X") || has("Gaze point left X"))
    {
        Some(Format::TobiiProLab)
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

fn delimiter(header: &str) -> u8 {
    let count = |c: char| header.matches(c).count();
    [(b'\t', count('\t')), (b';', count(';')), (b',', count(','))]
        .into_iter()
        .max_by_key(|&(d, n)| (n, d == b'\t'))
        .map_or(b',', |(d, _)| d)
}

/// One eye's columns.
#[derive(Debug, Clone, Copy)]
struct EyeCols {
    x: usize,
    y: usize,
    pupil: Option<usize>,
    /// Track loss when this column says "Invalid" (Pro Lab) or 1 (Data Viewer blink).
    lost: Option<usize>,
    /// A saccade when this column says 1 (Data Viewer).
    saccade: Option<usize>,
}

/// Where a format keeps what we read.
struct Spec {
    time: usize,
    time_scale: f64,
    /// Left, right; a monocular format of unknown eye uses the first.
    eyes: [Option<EyeCols>; 2],
    confidence: Option<usize>,
    /// Divide x and y by these (pixels → fraction of the screen), after `flip_y`.
    scale: (f64, f64),
    flip_y: bool,
    /// Pro Lab: "Saccade" in this column labels the sample.
    movement: Option<usize>,
    /// Pro Lab: rows whose sensor is not the eye tracker are skipped.
    sensor: Option<usize>,
    pupil_unit: Option<PupilUnit>,
}

struct Cells<'a> {
    record: &'a csv::StringRecord,
    decimal_comma: bool,
    line: usize,
    header: &'a [String],
}

impl Cells<'_> {
    fn text(&self, k: usize) -> &str {
        self.record.get(k).unwrap_or("").trim()
    }

    /// A number, or None for an empty, `.`, NaN or infinite cell (no value).
    fn number(&self, k: usize) -> Result<Option<f64>, FormatError> {
        let v = self.text(k);
        if v.is_empty() || v == "." || v.eq_ignore_ascii_case("nan") {
            return Ok(None);
        }
        let owned;
        let v = if self.decimal_comma && v.contains(',') {
            owned = v.replace(',', ".");
            owned.as_str()
        } else {
            v
        };
        v.parse::<f64>()
            .map(|n| n.is_finite().then_some(n))
            .map_err(|_| FormatError::NotNumeric {
                line: self.line,
                column: self.header.get(k).cloned().unwrap_or_else(|| "?".into()),
                value: self.text(k).to_string(),
            })
    }
}

fn reader(text: &str, delimiter: u8) -> csv::Reader<&[u8]> {
    csv::ReaderBuilder::new()
        .delimiter(delimiter)
        .flexible(true)
        .has_headers(true)
        .from_reader(text.as_bytes())
}

fn malformed(e: csv::Error) -> FormatError {
    let line = e.position().map_or(0, |p| p.line() as usize);
    FormatError::Malformed {
        line,
        what: e.to_string(),
    }
}

pub fn read(text: &str, opts: &ParseOptions) -> Result<Raw, FormatError> {
    let text = text.trim_start_matches('\u{feff}');
    let header_line = text
        .lines()
        .find(|l| !l.trim().is_empty())
        .ok_or(FormatError::Empty)?;
    let delimiter = delimiter(header_line);
    let mut rdr = reader(text, delimiter);
    let header: Vec<String> = rdr
        .headers()
        .map_err(malformed)?
        .iter()
        .map(|h| h.trim().to_string())
        .collect();
    let names: Vec<&str> = header.iter().map(String::as_str).collect();
    let format = match opts.format {
        Some(f) => f,
        None => detect(&names).ok_or_else(|| FormatError::Unknown {
            header: header_line.to_string(),
        })?,
    };
    // Decimal commas: only where the comma is not the delimiter, seen in the first rows.
    let decimal_comma = delimiter != b','
        && reader(text, delimiter)
            .records()
            .take(50)
            .flatten()
            .any(|r| {
                r.iter().any(|f| {
                    let f = f.trim();
                    f.split_once(',').is_some_and(|(a, b)| {
                        !a.is_empty()
                            && !b.is_empty()
                            && a.trim_start_matches('-')
                                .bytes()
                                .all(|c| c.is_ascii_digit())
                            && b.bytes().all(|c| c.is_ascii_digit())
                    })
                })
            });
    let first = reader(text, delimiter)
        .records()
        .next()
        .transpose()
        .map_err(malformed)?;
    let spec = spec(format, &names, opts, first.as_ref(), header_line)?;
    let mut rows = Vec::new();
    let mut saccade_flags = Vec::new();
    for record in rdr.records() {
        let record = record.map_err(malformed)?;
        if record.iter().all(|f| f.trim().is_empty()) {
            continue;
        }
        let line = record.position().map_or(0, |p| p.line() as usize);
        let cells = Cells {
            record: &record,
            decimal_comma,
            line,
            header: &header,
        };
        if let Some(k) = spec.sensor {
            let s = cells.text(k);
            if !s.is_empty() && !s.eq_ignore_ascii_case("Eye Tracker") {
                continue;
            }
        }
        let Some(t) = cells.number(spec.time)? else {
            return Err(FormatError::NotNumeric {
                line,
                column: header[spec.time].clone(),
                value: cells.text(spec.time).to_string(),
            });
        };
        let confident = match spec.confidence {
            Some(k) => cells.number(k)?.is_some_and(|c| c >= opts.min_confidence),
            None => true,
        };
        let mut eyes = [EyeSample::default(); 2];
        let mut saccade = spec
            .movement
            .is_some_and(|k| cells.text(k).eq_ignore_ascii_case("Saccade"));
        for (slot, cols) in eyes.iter_mut().zip(spec.eyes) {
            let Some(c) = cols else { continue };
            let lost = c.lost.is_some_and(|k| {
                let v = cells.text(k);
                v.eq_ignore_ascii_case("Invalid") || v == "1"
            });
            saccade |= c.saccade.is_some_and(|k| cells.text(k) == "1");
            let (x, y) = (cells.number(c.x)?, cells.number(c.y)?);
            slot.xy = match (x, y, confident && !lost) {
                (Some(x), Some(y), true) => {
                    let (nx, ny) = (x / spec.scale.0, y / spec.scale.1);
                    Some([nx, if spec.flip_y { 1.0 - ny } else { ny }])
                }
                _ => None,
            };
            slot.pupil = match c.pupil {
                Some(k) if !lost => cells.number(k)?.filter(|p| *p > 0.0),
                _ => None,
            };
        }
        saccade_flags.push(saccade);
        rows.push(Row {
            line,
            t_ms: t * spec.time_scale,
            eyes,
        });
    }
    let labelled =
        spec.movement.is_some() || spec.eyes.iter().flatten().any(|e| e.saccade.is_some());
    let saccades = labelled.then(|| intervals(&rows, &saccade_flags));
    Ok(Raw {
        format,
        rows,
        eyes: [spec.eyes[0].is_some(), spec.eyes[1].is_some()],
        pupil_unit: spec.pupil_unit,
        saccades,
        screen: None,
    })
}

/// Runs of labelled rows as (first, last) times.
fn intervals(rows: &[Row], flags: &[bool]) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::new();
    let mut open = false;
    for (row, &f) in rows.iter().zip(flags) {
        match (f, open, out.last_mut()) {
            (true, true, Some(last)) => last.1 = row.t_ms,
            (true, _, _) => out.push((row.t_ms, row.t_ms)),
            _ => {}
        }
        open = f;
    }
    out
}

fn spec(
    format: Format,
    names: &[&str],
    opts: &ParseOptions,
    first: Option<&csv::StringRecord>,
    header_line: &str,
) -> Result<Spec, FormatError> {
    let find = |n: &str| names.iter().position(|h| *h == n);
    let col = |n: &str| {
        find(n).ok_or_else(|| FormatError::MissingColumn {
            format,
            column: n.to_string(),
            header: header_line.to_string(),
        })
    };
    let screen = |default: Option<(f64, f64)>| -> Result<(f64, f64), FormatError> {
        match (opts.screen, default) {
            (Some((w, h)), _) => Ok((f64::from(w), f64::from(h))),
            (None, Some(d)) => Ok(d),
            (None, None) => Err(FormatError::NeedsScreen(format)),
        }
    };
    let eye = |x: &str, y: &str, p: Option<&str>| {
        Some(EyeCols {
            x: find(x)?,
            y: find(y)?,
            pupil: p.and_then(find),
            lost: None,
            saccade: None,
        })
    };
    let mut s = Spec {
        time: 0,
        time_scale: 1.0,
        eyes: [None, None],
        confidence: None,
        scale: (1.0, 1.0),
        flip_y: false,
        movement: None,
        sensor: None,
        pupil_unit: None,
    };
    match format {
        Format::Eyelink => {
            s.time = col("t_s")?;
            s.time_scale = 1e3;
            s.pupil_unit = Some(PupilUnit::Area);
            s.scale = screen(None)?;
            let pair = |a: &str, b: &str| {
                eye(&format!("xpos{a}"), &format!("ypos{a}"), Some(&format!("ps{a}")))
                    .or_else(|| eye(&format!("xpos{b}"), &format!("ypos{b}"), Some(&format!("ps{b}"))))
            };
            s.eyes = [pair("_l", "_left"), pair("_r", "_right")];
            if s.eyes.iter().all(Option::is_none) {
                s.eyes[0] = Some(EyeCols { x: col("xpos")?, y: col("ypos")?, pupil: find("ps"), lost: None, saccade: None });
            }
        }
        Format::DataViewer => {
            s.time = col("TIMESTAMP")?;
            s.pupil_unit = Some(PupilUnit::Area);
            s.scale = screen(None)?;
            for (slot, side) in s.eyes.iter_mut().zip(["LEFT", "RIGHT"]) {
                *slot = eye(&format!("{side}_GAZE_X"), &format!("{side}_GAZE_Y"), Some(&format!("{side}_PUPIL_SIZE")))
                    .map(|e| EyeCols { lost: find(&format!("{side}_IN_BLINK")), saccade: find(&format!("{side}_IN_SACCADE")), ..e });
            }
            // A monocular report keeps the other eye's columns, all ".": data decides later.
            if s.eyes.iter().all(Option::is_none) {
                return Err(FormatError::MissingColumn {
                    format,
                    column: "LEFT_GAZE_X and LEFT_GAZE_Y, or RIGHT_GAZE_X and RIGHT_GAZE_Y".into(),
                    header: header_line.to_string(),
                });
            }
        }
        Format::TobiiProLab => {
            let t = names
                .iter()
                .position(|h| h.starts_with("Recording timestamp"))
                .ok_or_else(|| FormatError::MissingColumn { format, column: "Recording timestamp".into(), header: header_line.to_string() })?;
            s.time = t;
            s.time_scale = if names[t].contains("μs") || names[t].contains("us]") { 1e-3 } else { 1.0 };
            s.pupil_unit = Some(PupilUnit::Mm);
            let resolution = first.and_then(|r| {
                let w: f64 = r.get(find("Recording resolution width")?)?.trim().parse().ok()?;
                let h: f64 = r.get(find("Recording resolution height")?)?.trim().parse().ok()?;
                (w > 0.0 && h > 0.0).then_some((w, h))
            });
            s.scale = screen(resolution)?;
            s.movement = find("Eye movement type");
            s.sensor = find("Sensor");
            for (slot, side) in s.eyes.iter_mut().zip(["left", "right"]) {
                *slot = eye(&format!("Gaze point {side} X"), &format!("Gaze point {side} Y"), Some(&format!("Pupil diameter {side}")))
                    .map(|e| EyeCols { lost: find(&format!("Validity {side}")), ..e });
            }
            if s.eyes.iter().all(Option::is_none) {
                s.eyes[0] = eye("Gaze point X", "Gaze point Y", None);
            }
            if s.eyes.iter().all(Option::is_none) {
                col("Gaze point X")?;
            }
        }
        Format::PupilCore => {
            s.time = col("gaze_timestamp")?;
            s.time_scale = 1e3;
            s.eyes[0] = Some(EyeCols { x: col("norm_pos_x")?, y: col("norm_pos_y")?, pupil: None, lost: None, saccade: None });
            s.confidence = find("confidence");
            s.flip_y = true;
        }
        Format::PupilNeon => {
            s.time = col("timestamp [ns]")?;
            s.time_scale = 1e-6;
            s.eyes[0] = Some(EyeCols { x: col("gaze x [px]")?, y: col("gaze y [px]")?, pupil: None, lost: None, saccade: None });
            s.scale = screen(Some((1600.0, 1200.0)))?;
        }
        Format::Tobii => {
            s.time = col("device_time_stamp")?;
            s.time_scale = 1e-3;
            s.eyes[0] = Some(EyeCols { x: col("gaze_point_x")?, y: col("gaze_point_y")?, pupil: find("pupil_diameter"), lost: None, saccade: None });
            s.pupil_unit = Some(PupilUnit::Mm);
        }
        Format::Generic => {
            let c = &opts.columns;
            s.time_scale = match c.time_unit.as_str() {
                "s" => 1e3,
                "ms" => 1.0,
                "us" => 1e-3,
                "ns" => 1e-6,
                other => return Err(FormatError::TimeUnit(other.to_string())),
            };
            s.time = col(&c.time)?;
            s.eyes[0] = Some(EyeCols { x: col(&c.x)?, y: col(&c.y)?, pupil: c.pupil.as_deref().and_then(find), lost: None, saccade: None });
            s.pupil_unit = Some(PupilUnit::Mm);
            if c.pixels {
                s.scale = screen(None)?;
            }
        }
        Format::EyelinkAsc => {
            return Err(FormatError::Malformed {
                line: 1,
                what: "an ASC file has no header row; it is read as ASC only when it looks like one (a START or SAMPLES line)".into(),
            })
        }
    }
    Ok(s)
}
