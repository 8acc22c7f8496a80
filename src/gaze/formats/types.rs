//! What the format parsers take and give: the formats, column mapping, options, errors and
//! the parsed recording.

use crate::gaze::Sample;

#[derive(
    Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize, clap::ValueEnum,
)]
#[serde(rename_all = "snake_case")]
#[value(rename_all = "snake_case")]
pub enum Format {
    /// The CSV layout of `../shared/data/gaze` (converted from EDF): `t_s, xpos, ypos, ps`, or
    /// binocular `xpos_l, ypos_l, ps_l, xpos_r, …` (`_left`/`_right` too): seconds, pixels on
    /// a stated screen, pupil AREA (arbitrary units).
    Eyelink,
    /// EyeLink ASC (edf2asc): sample lines `time x y pupil …` or binocular `time xl yl pl xr yr
    /// pr …` with `.` for missing values; `SAMPLES GAZE LEFT RIGHT` says the eyes, `PUPIL AREA`
    /// or `PUPIL DIAMETER` the pupil, `MSG … DISPLAY_COORDS` the screen; `ESACC` events label
    /// saccades and `EBLINK` events mark blinks.
    EyelinkAsc,
    /// EyeLink Data Viewer sample report (TSV): `TIMESTAMP` (ms), `LEFT_/RIGHT_GAZE_X/Y`
    /// (pixels), `LEFT_/RIGHT_PUPIL_SIZE` (area unless --pupil-unit says), `…_IN_BLINK`,
    /// `…_IN_SACCADE`; `.` for missing values.
    DataViewer,
    /// `gaze_timestamp, norm_pos_x, norm_pos_y, confidence`: seconds, normalised with the origin
    /// at the BOTTOM left, confidence in [0, 1].
    PupilCore,
    /// `timestamp [ns], gaze x [px], gaze y [px]`: scene-camera pixels (1600×1200 unless stated).
    PupilNeon,
    /// `device_time_stamp, gaze_point_x, gaze_point_y, pupil_diameter`: µs, normalised
    /// (top-left), mm.
    Tobii,
    /// Tobii Pro Lab data export (TSV): `Recording timestamp` (µs when the header says `[μs]`,
    /// else ms), `Gaze point X/Y` or per eye `Gaze point left/right X/Y` (pixels on
    /// `Recording resolution width/height`), `Pupil diameter left/right` (mm), `Validity
    /// left/right`, `Eye movement type` (its saccades label samples), `Sensor` (rows of other
    /// sensors are skipped).
    TobiiProLab,
    /// Columns named by `Columns` (defaults `t_ms, x, y, pupil_mm`), normalised coordinates.
    Generic,
}

/// Which eye of a binocular recording to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum Eye {
    Left,
    Right,
    /// The mean of both eyes where both are tracked, the one that is where only one is.
    #[default]
    Average,
}

/// What a pupil column holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum PupilUnit {
    /// Diameter in millimetres (Tobii, Pupil Labs, our own recordings).
    Mm,
    /// Diameter in arbitrary units: scaled so the recording's median is `pupil_median_mm`.
    Diameter,
    /// Area in arbitrary units (EyeLink's default): diameter ∝ √area, then scaled as above.
    Area,
}

/// Column mapping for the generic format.
#[derive(Debug, Clone, PartialEq)]
pub struct Columns {
    pub time: String,
    pub x: String,
    pub y: String,
    pub pupil: Option<String>,
    /// Time unit of the time column: s, ms, us or ns.
    pub time_unit: String,
    /// Coordinates in pixels (needs a screen size) instead of normalised.
    pub pixels: bool,
}

impl Default for Columns {
    fn default() -> Self {
        Columns {
            time: "t_ms".into(),
            x: "x".into(),
            y: "y".into(),
            pupil: Some("pupil_mm".into()),
            time_unit: "ms".into(),
            pixels: false,
        }
    }
}

/// Everything a parse needs besides the text.
#[derive(Debug, Clone, PartialEq)]
pub struct ParseOptions {
    pub format: Option<Format>,
    /// Screen size in pixels, for formats in pixels.
    pub screen: Option<(u32, u32)>,
    pub columns: Columns,
    /// EyeLink pupil areas are mapped to diameters so that the recording's median is this many mm.
    pub pupil_median_mm: f64,
    /// Pupil Labs Core samples below this confidence count as track loss.
    pub min_confidence: f64,
    /// Which eye of a binocular recording (default: the average, or the only eye recorded).
    pub eye: Option<Eye>,
    /// What the pupil column holds, where the format does not say (default: the format's own
    /// unit; mm for the generic format).
    pub pupil_unit: Option<PupilUnit>,
}

impl Default for ParseOptions {
    fn default() -> Self {
        ParseOptions {
            format: None,
            screen: None,
            columns: Columns::default(),
            pupil_median_mm: 4.0,
            min_confidence: 0.6,
            eye: None,
            pupil_unit: None,
        }
    }
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FormatError {
    #[error("the file is empty")]
    Empty,
    #[error("cannot tell the format from the header {header:?}; say --format (eyelink, eyelink_asc, data_viewer, pupil_core, pupil_neon, tobii, tobii_pro_lab, generic)")]
    Unknown { header: String },
    #[error("{format:?} needs column {column:?}, which the header {header:?} lacks")]
    MissingColumn {
        format: Format,
        column: String,
        header: String,
    },
    #[error("line {line}: {column} = {value:?} is not a number")]
    NotNumeric {
        line: usize,
        column: String,
        value: String,
    },
    #[error("line {line}: time {t} goes back from {previous} (samples must be in time order)")]
    Unsorted { line: usize, t: f64, previous: f64 },
    #[error("line {line}: time {t} repeats the previous sample's time")]
    Duplicate { line: usize, t: f64 },
    #[error("{0:?} coordinates are in pixels: give the screen size (--screen WxH)")]
    NeedsScreen(Format),
    #[error("unknown time unit {0:?} (s, ms, us, ns)")]
    TimeUnit(String),
    #[error("the file has a header but no samples")]
    NoSamples,
    #[error("--eye {asked:?}: the recording has only the {has} eye")]
    EyeMissing { asked: Eye, has: &'static str },
    #[error("line {line}: {what}")]
    Malformed { line: usize, what: String },
    #[error("line {line}: time {t} ms is {days:.0} days after the first sample; Fovea replays at most {MAX_SPAN_DAYS} days (is --time-unit right?)")]
    TooLong { line: usize, t: f64, days: f64 },
}

/// The longest recording Fovea takes, first sample to last: a bound that keeps schedules and
/// timers finite (a stray 1e300 timestamp would overflow them).
pub const MAX_SPAN_DAYS: f64 = 7.0;

/// The parsed recording and what was decided on the way, to print for the user.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    pub format: Format,
    pub samples: Vec<Sample>,
    /// How pupil values were turned into millimetres, if they were.
    pub pupil_rule: Option<String>,
    /// The eye used, for binocular recordings.
    pub eye: Option<Eye>,
    /// The screen size the file states (ASC `DISPLAY_COORDS`, Pro Lab's recording resolution).
    pub screen: Option<(u32, u32)>,
    /// The recording's own saccade events (ms from the first sample), where the format has
    /// them (EyeLink ASC `ESACC`); scoring labels samples with them instead of by velocity.
    pub saccades: Option<Vec<(f64, f64)>>,
}
