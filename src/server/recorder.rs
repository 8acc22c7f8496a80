//! Session recording: a session's received gaze samples, in the generic CSV format
//! (`t_ms, x, y, pupil_mm`), written as they arrive to `session-<id>.csv.partial` and renamed
//! to `session-<id>.csv` when the session ends, so a finished file is always whole.
//!
//! Each server run records into its own folder, `run-<unix seconds>-<random>`, so session ids
//! that restart at 1 never overwrite an earlier run's files. A run that was killed leaves
//! `.partial` files; the next start recovers them (`recover`): the cut last row is trimmed and
//! the file renamed to `session-<id>.recovered.csv`.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use crate::protocol::Gaze;

pub struct Recorder {
    writer: BufWriter<File>,
    partial: PathBuf,
    path: PathBuf,
    /// Times are written relative to the first sample.
    t0: Option<f64>,
    /// The last row's time, from `t0`.
    last_t: Option<f64>,
    error: Option<std::io::Error>,
    flushed: std::time::Instant,
    /// Bytes written so far, and the most the file may hold.
    written: u64,
    max_bytes: u64,
    /// What the whole recording folder may still take, shared by every session's recorder.
    folder: Arc<Quota>,
}

/// Bytes the recording folder may still take (`--record-dir-max-mb` less what it held at start).
#[derive(Debug)]
pub struct Quota(AtomicU64);

impl Quota {
    /// The folder's limit less what `dir` holds now (every file under it, counted once).
    pub fn for_folder(dir: &Path, max_bytes: u64) -> Quota {
        Quota(AtomicU64::new(max_bytes.saturating_sub(folder_bytes(dir))))
    }

    /// Takes `n` bytes if that many are left. A compare-exchange loop, as `fetch_update` is:
    /// Rust 1.95 deprecates that name for `try_update`, which our minimum (1.90) lacks, and a
    /// fresh install's build warned.
    fn take(&self, n: u64) -> bool {
        let mut left = self.0.load(Ordering::SeqCst);
        while let Some(rest) = left.checked_sub(n) {
            match self
                .0
                .compare_exchange_weak(left, rest, Ordering::SeqCst, Ordering::SeqCst)
            {
                Ok(_) => return true,
                Err(now) => left = now,
            }
        }
        false
    }
}

/// Total size of the files under `dir` (two levels: run folders and their files).
fn folder_bytes(dir: &Path) -> u64 {
    let size = |p: &Path| std::fs::metadata(p).map_or(0, |m| if m.is_file() { m.len() } else { 0 });
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    entries
        .flatten()
        .map(|e| {
            let p = e.path();
            if p.is_dir() {
                std::fs::read_dir(&p)
                    .map(|inner| inner.flatten().map(|f| size(&f.path())).sum())
                    .unwrap_or(0)
            } else {
                size(&p)
            }
        })
        .sum()
}

/// What a `write` did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wrote {
    Row,
    /// The row would pass the file's size limit: not written, and nothing more will be.
    LimitReached,
    /// The row would pass the recording folder's limit: the same, for the folder.
    FolderFull,
    /// The recording had already stopped (limit or write error).
    Nothing,
}

impl Recorder {
    pub fn create(
        dir: &Path,
        session: u64,
        max_bytes: u64,
        folder: Arc<Quota>,
    ) -> std::io::Result<Recorder> {
        const HEADER: &[u8] = b"t_ms,x,y,pupil_mm\n";
        if !folder.take(HEADER.len() as u64) {
            return Err(std::io::Error::other(
                "the recording folder is at its limit (--record-dir-max-mb)",
            ));
        }
        let path = dir.join(format!("session-{session}.csv"));
        let partial = dir.join(format!("session-{session}.csv.partial"));
        let mut writer = BufWriter::new(File::create(&partial)?);
        writer.write_all(HEADER)?;
        // The header reaches the file at once: a download before the first second is never empty.
        writer.flush()?;
        Ok(Recorder {
            writer,
            partial,
            path,
            t0: None,
            last_t: None,
            error: None,
            flushed: std::time::Instant::now(),
            written: HEADER.len() as u64,
            max_bytes,
            folder,
        })
    }

    /// Where the file is while the session lives, and where it goes when it ends.
    pub fn paths(&self) -> (PathBuf, PathBuf) {
        (self.partial.clone(), self.path.clone())
    }

    /// Appends one sample; the first write error is kept and reported by `finish`. A row that
    /// would take the file past `max_bytes` stops the recording instead.
    pub fn write(&mut self, g: &Gaze) -> Wrote {
        if self.error.is_some() || self.written > self.max_bytes {
            return Wrote::Nothing;
        }
        // The sample's own time where the client sent it (a replay does), so replaying the
        // recording reproduces the original timing rather than the network's.
        let t = g.sample_t_ms.unwrap_or(g.t_ms);
        let t0 = *self.t0.get_or_insert(t);
        if self.last_t.is_some_and(|last| t - t0 <= last) {
            // A time that does not move on would make the file unreplayable: not written.
            return Wrote::Nothing;
        }
        self.last_t = Some(t - t0);
        let pupil = g.pupil_mm.map(|p| p.to_string()).unwrap_or_default();
        let row = format!("{},{},{},{}\n", t - t0, g.x, g.y, pupil);
        if self.written + row.len() as u64 > self.max_bytes {
            // Past the limit the file stays whole and stops; `written` marks it stopped.
            self.written = self.max_bytes + 1;
            return Wrote::LimitReached;
        }
        if !self.folder.take(row.len() as u64) {
            self.written = self.max_bytes + 1;
            return Wrote::FolderFull;
        }
        if let Err(e) = self.writer.write_all(row.as_bytes()) {
            self.error = Some(e);
            return Wrote::Nothing;
        }
        self.written += row.len() as u64;
        if self.flushed.elapsed() >= std::time::Duration::from_secs(1) {
            self.flush();
        }
        Wrote::Row
    }

    /// Writes out buffered rows (the session calls it every second, so rows reach the file
    /// within a second even when samples stop coming).
    pub fn flush(&mut self) {
        if self.error.is_none() {
            if let Err(e) = self.writer.flush() {
                self.error = Some(e);
            }
            self.flushed = std::time::Instant::now();
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

/// Makes this run's folder inside `dir` after recovering what killed runs left there.
pub fn start_run(dir: &Path) -> std::io::Result<PathBuf> {
    std::fs::create_dir_all(dir)?;
    for file in recover(dir)? {
        tracing::warn!(
            "recovered the recording a stopped run left: {}",
            file.display()
        );
    }
    let run = dir.join(run_folder_name());
    std::fs::create_dir(&run)?;
    tracing::info!("recording sessions to {}", run.display());
    Ok(run)
}

/// A new run's folder name: start time and 32 random bits.
pub fn run_folder_name() -> String {
    use std::hash::BuildHasher;
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let random = std::collections::hash_map::RandomState::new().hash_one(std::process::id()) as u32;
    format!("run-{now}-{random:08x}")
}

/// Recovers the `.partial` recordings that earlier runs under `dir` left (a crash or SIGKILL):
/// keeps every complete row, drops a cut last row, and renames each to
/// `<name>.recovered.csv`. Returns the files recovered.
pub fn recover(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut recovered = Vec::new();
    for run in std::fs::read_dir(dir)? {
        let run = run?.path();
        if !run.is_dir() {
            continue;
        }
        for entry in std::fs::read_dir(&run)? {
            let path = entry?.path();
            let Some(stem) = path
                .file_name()
                .and_then(|n| n.to_str())
                .and_then(|n| n.strip_suffix(".csv.partial"))
            else {
                continue;
            };
            let bytes = std::fs::read(&path)?;
            // Rows end with a newline; whatever follows the last one is a row cut short.
            let whole = bytes.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
            let target = run.join(format!("{stem}.recovered.csv"));
            std::fs::write(&target, &bytes[..whole])?;
            std::fs::remove_file(&path)?;
            recovered.push(target);
        }
    }
    Ok(recovered)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_killed_runs_partial_files_keep_their_whole_rows() {
        let dir = std::env::temp_dir().join(format!("fovea-recover-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let run = dir.join("run-1-0");
        std::fs::create_dir_all(&run).unwrap();
        std::fs::write(
            run.join("session-3.csv.partial"),
            "t_ms,x,y,pupil_mm\n0,0.5,0.5,4\n4,0.5",
        )
        .unwrap();
        std::fs::write(run.join("session-4.csv.partial"), "t_ms,x,y,pupil_mm\n").unwrap();
        std::fs::write(run.join("session-1.csv"), "t_ms,x,y,pupil_mm\n").unwrap();
        let mut got = recover(&dir).unwrap();
        got.sort();
        assert_eq!(
            got,
            [
                run.join("session-3.recovered.csv"),
                run.join("session-4.recovered.csv")
            ]
        );
        assert_eq!(
            std::fs::read_to_string(&got[0]).unwrap(),
            "t_ms,x,y,pupil_mm\n0,0.5,0.5,4\n"
        );
        assert!(!run.join("session-3.csv.partial").exists());
        assert!(
            run.join("session-1.csv").exists(),
            "finished files are left alone"
        );
        assert!(recover(&dir).unwrap().is_empty(), "recovery is done once");
        assert_ne!(
            run_folder_name(),
            run_folder_name(),
            "two runs never share a folder"
        );

        // A recording stops whole at its limit.
        let unlimited = Arc::new(Quota(AtomicU64::new(u64::MAX)));
        let mut r = Recorder::create(&run, 9, 80, unlimited).unwrap();
        let g = |t: f64| Gaze {
            seq: 1,
            t_ms: t,
            x: 0.25,
            y: 0.5,
            pupil_mm: Some(4.0),
            sample_t_ms: None,
        };
        let wrote: Vec<Wrote> = (0..6).map(|i| r.write(&g(f64::from(i)))).collect();
        assert_eq!(
            wrote,
            [
                Wrote::Row,
                Wrote::Row,
                Wrote::Row,
                Wrote::Row,
                Wrote::LimitReached,
                Wrote::Nothing
            ]
        );
        let text = std::fs::read_to_string(r.finish().unwrap()).unwrap();
        assert!(text.len() <= 80 && text.ends_with('\n'), "{text:?}");
        // 18 bytes of header and four 13-byte rows fit in 80; a fifth would not.
        assert_eq!(text.lines().count(), 5, "{text:?}");

        // The folder's limit counts what is there and what every recorder writes: the header
        // and two rows of this one fit, and no further recording can start.
        let held = folder_bytes(&dir);
        assert!(held > 80, "{held}");
        let quota = Arc::new(Quota::for_folder(&dir, held + 18 + 2 * 13));
        let mut r = Recorder::create(&run, 10, 1 << 20, quota.clone()).unwrap();
        let wrote: Vec<Wrote> = (0..4).map(|i| r.write(&g(f64::from(i)))).collect();
        assert_eq!(
            wrote,
            [Wrote::Row, Wrote::Row, Wrote::FolderFull, Wrote::Nothing]
        );
        assert!(Recorder::create(&run, 11, 1 << 20, quota).is_err());
        let text = std::fs::read_to_string(r.finish().unwrap()).unwrap();
        assert_eq!(text.lines().count(), 3, "{text:?}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Sessions record on threads of their own: taken together they never overdraw the folder,
    /// and they stop only when what is left is less than one more take.
    #[test]
    fn a_quota_shared_by_threads_is_never_overdrawn() {
        let quota = Arc::new(Quota(AtomicU64::new(1000)));
        let takers: Vec<_> = (0..8)
            .map(|_| {
                let q = quota.clone();
                std::thread::spawn(move || (0..200).filter(|_| q.take(7)).count() as u64)
            })
            .collect();
        let taken: u64 = takers.into_iter().map(|t| t.join().unwrap()).sum();
        assert_eq!(taken, 1000 / 7);
        assert_eq!(quota.0.load(Ordering::SeqCst), 1000 % 7);
    }

    /// Record → replay keeps the recording's timing: samples reach the server late by a
    /// jitter up to a 60 Hz frame (as a browser's event loop or a busy network delivers them),
    /// and the recording still holds each sample's own time, so replaying it sends every
    /// sample within 0.5 ms of when the tracker took it (median). Measured on tokio's paused
    /// clock: a fake clock, so the figure is the scheduler's and not this machine's load.
    /// (Tokio's timers tick in whole milliseconds, so a sample at a fraction of one goes at the
    /// nearest tick: the quarter-millisecond times here show that.) Recording the arrival time
    /// instead, as before, is off by the jitter.
    #[tokio::test(start_paused = true)]
    async fn a_recording_replays_with_its_own_timing() {
        use crate::client::replay::{pace, schedule};
        use crate::gaze::Sample;
        let original: Vec<Sample> = (0..2000)
            .map(|i| Sample {
                t_ms: f64::from(i) * 1.0 + 0.25 * f64::from(i % 3),
                xy: Some([0.5, 0.5]),
                pupil_mm: None,
            })
            .collect();
        let dir = std::env::temp_dir().join(format!("fovea-timing-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let quota = Arc::new(Quota(AtomicU64::new(u64::MAX)));
        let mut own = Recorder::create(&dir, 1, 1 << 30, quota.clone()).unwrap();
        let mut arrival = Recorder::create(&dir, 2, 1 << 30, quota).unwrap();
        let plan = schedule(&original, 1.0, 0.0, None, 1);
        let start = tokio::time::Instant::now();
        let mut seq = 0u64;
        let mut last_arrival = f64::NEG_INFINITY;
        pace(start, &plan, |_, at_ms| {
            seq += 1;
            let sent = start.elapsed().as_secs_f64() * 1e3;
            // Deterministic jitter of 0–16 ms; a connection delivers in order, so a sample
            // arrives no earlier than the one before it.
            let jitter = 16.0 * ((seq * 7919) % 97) as f64 / 97.0;
            let arrived = (sent + jitter).max(last_arrival + 1e-3);
            last_arrival = arrived;
            let g = |sample_t_ms| Gaze {
                seq,
                t_ms: arrived,
                x: 0.5,
                y: 0.5,
                pupil_mm: None,
                sample_t_ms,
            };
            own.write(&g(Some(at_ms)));
            arrival.write(&g(None));
            true
        })
        .await;
        // Replays each file on the fake clock and returns its median timing error, ms.
        let original = &original;
        let error = |path: PathBuf| {
            let text = std::fs::read_to_string(path).unwrap();
            let recorded = crate::gaze::formats::parse(&text, &Default::default()).unwrap();
            let replan = schedule(&recorded.samples, 1.0, 0.0, None, 1);
            async move {
                let start = tokio::time::Instant::now();
                let mut errors = Vec::new();
                pace(start, &replan, |i, _| {
                    let at = start.elapsed().as_secs_f64() * 1e3;
                    errors.push((at - original[i].t_ms).abs());
                    true
                })
                .await;
                errors.sort_by(|a, b| a.total_cmp(b));
                errors[errors.len() / 2]
            }
        };
        let kept = error(own.finish().unwrap()).await;
        let arrived = error(arrival.finish().unwrap()).await;
        assert!(kept <= 0.5, "median timing error {kept} ms");
        assert!(
            arrived > 1.0 && arrived > 4.0 * kept,
            "the arrival-time recording is off: {arrived} ms against {kept} ms"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
