//! Session recording: a session's received gaze samples, in the generic CSV format
//! (`t_ms, x, y, pupil_mm`), written as they arrive to `session-<id>.csv.partial` and renamed
//! to `session-<id>.csv` when the session ends, so a finished file is always whole and a crash
//! leaves the partial one for inspection.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::protocol::Gaze;

pub struct Recorder {
    writer: BufWriter<File>,
    partial: PathBuf,
    path: PathBuf,
    /// Times are written relative to the first sample.
    t0: Option<f64>,
    error: Option<std::io::Error>,
    flushed: std::time::Instant,
}

impl Recorder {
    pub fn create(dir: &Path, session: u64) -> std::io::Result<Recorder> {
        let path = dir.join(format!("session-{session}.csv"));
        let partial = dir.join(format!("session-{session}.csv.partial"));
        let mut writer = BufWriter::new(File::create(&partial)?);
        writer.write_all(b"t_ms,x,y,pupil_mm\n")?;
        // The header reaches the file at once: a download before the first second is never empty.
        writer.flush()?;
        Ok(Recorder {
            writer,
            partial,
            path,
            t0: None,
            error: None,
            flushed: std::time::Instant::now(),
        })
    }

    /// Where the file is while the session lives, and where it goes when it ends.
    pub fn paths(&self) -> (PathBuf, PathBuf) {
        (self.partial.clone(), self.path.clone())
    }

    /// Appends one sample; the first write error is kept and reported by `finish`. Rows reach
    /// the file at least once a second, so a download mid-session is at most a second behind.
    pub fn write(&mut self, g: &Gaze) {
        if self.error.is_some() {
            return;
        }
        let t0 = *self.t0.get_or_insert(g.t_ms);
        let pupil = g.pupil_mm.map(|p| p.to_string()).unwrap_or_default();
        if let Err(e) = writeln!(self.writer, "{},{},{},{}", g.t_ms - t0, g.x, g.y, pupil) {
            self.error = Some(e);
            return;
        }
        if self.flushed.elapsed() >= std::time::Duration::from_secs(1) {
            self.flushed = std::time::Instant::now();
            if let Err(e) = self.writer.flush() {
                self.error = Some(e);
            }
        }
    }

    /// Flushes, syncs and renames into place.
    pub fn finish(mut self) -> std::io::Result<PathBuf> {
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        self.writer.flush()?;
        self.writer.get_ref().sync_all()?;
        std::fs::rename(&self.partial, &self.path)?;
        Ok(self.path)
    }
}
