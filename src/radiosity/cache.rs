//! The solve runs once per distinct scene input, on its own thread: every renderer, session and
//! frame that shows the same geometry and lights shares it, and sees its snapshots improve
//! until it converges. A scene whose geometry or lights change has a different key and solves
//! anew; when nobody holds a handle any more, the thread stops at its next snapshot.

use std::collections::hash_map::DefaultHasher;
use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex, OnceLock, Weak};
use std::time::{Duration, Instant};

use super::{Options, RadiosityError, Solver, Stats, Surface};

/// How often a converging solve publishes its state.
const SNAPSHOT_EVERY: Duration = Duration::from_millis(250);

/// Per-vertex irradiance at one point of the solve, ready to upload.
#[derive(Debug, Clone)]
pub struct Snapshot {
    /// 1, 2, … in publication order.
    pub version: u64,
    /// Per output vertex: direct irradiance (rgb, w = 0) and indirect irradiance including the
    /// ambient preview of the energy not yet shot.
    pub direct: Vec<[f32; 4]>,
    pub indirect: Vec<[f32; 4]>,
    pub stats: Stats,
    pub elapsed_s: f64,
    pub converged: bool,
}

/// The radiosity snapshot a frame was lit by (sent in frame headers).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Progress {
    pub shots: u32,
    pub elements: usize,
    /// Unshot power over emitted power (the ambient term previews it).
    pub unshot: f64,
    pub converged: bool,
}

impl Snapshot {
    pub fn progress(&self) -> Progress {
        Progress {
            shots: self.stats.shots,
            elements: self.stats.elements,
            unshot: self.stats.unshot_fraction,
            converged: self.converged,
        }
    }
}

struct Shared {
    scene: String,
    latest: Mutex<Option<Arc<Snapshot>>>,
    changed: Condvar,
    version: AtomicU64,
    done: AtomicBool,
    /// (seconds since start, stats) after every shot: the convergence curve.
    history: Mutex<Vec<(f64, Stats)>>,
}

/// A running or finished solve.
#[derive(Clone)]
pub struct RadiosityHandle {
    shared: Arc<Shared>,
}

fn cache() -> &'static Mutex<HashMap<u64, Weak<Shared>>> {
    static CACHE: OnceLock<Mutex<HashMap<u64, Weak<Shared>>>> = OnceLock::new();
    CACHE.get_or_init(|| Mutex::new(HashMap::new()))
}

/// A key that changes whenever anything the solve depends on changes.
fn key_of(surfaces: &[Surface], options: &Options) -> u64 {
    let mut h = DefaultHasher::new();
    format!("{surfaces:?}{options:?}").hash(&mut h);
    h.finish()
}

impl RadiosityHandle {
    /// The shared solve of these surfaces: an existing one, or a new thread.
    pub fn start(
        scene: &str,
        surfaces: Vec<Surface>,
        options: Options,
    ) -> Result<RadiosityHandle, RadiosityError> {
        let key = key_of(&surfaces, &options);
        let mut map = cache().lock().unwrap_or_else(|p| p.into_inner());
        if let Some(shared) = map.get(&key).and_then(Weak::upgrade) {
            return Ok(RadiosityHandle { shared });
        }
        let solver = Solver::new(&surfaces, options)?;
        let shared = Arc::new(Shared {
            scene: scene.to_string(),
            latest: Mutex::new(None),
            changed: Condvar::new(),
            version: AtomicU64::new(0),
            done: AtomicBool::new(false),
            history: Mutex::new(Vec::new()),
        });
        map.retain(|_, w| w.strong_count() > 0);
        map.insert(key, Arc::downgrade(&shared));
        let weak = Arc::downgrade(&shared);
        let name = scene.to_string();
        let spawned = std::thread::Builder::new()
            .name(format!("radiosity {name}"))
            .spawn(move || run(solver, weak, &name));
        if spawned.is_err() {
            tracing::error!(
                scene,
                "could not start the radiosity thread; the scene shows direct light only"
            );
        }
        Ok(RadiosityHandle { shared })
    }

    pub fn scene(&self) -> &str {
        &self.shared.scene
    }

    /// The newest snapshot, if one has been published yet.
    pub fn latest(&self) -> Option<Arc<Snapshot>> {
        self.shared
            .latest
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .clone()
    }

    pub fn version(&self) -> u64 {
        self.shared.version.load(Ordering::Acquire)
    }

    pub fn converged(&self) -> bool {
        self.shared.done.load(Ordering::Acquire)
    }

    /// Blocks until the solve converges (or `timeout` passes) and returns the newest snapshot.
    pub fn wait(&self, timeout: Duration) -> Option<Arc<Snapshot>> {
        let deadline = Instant::now() + timeout;
        let mut guard = self.shared.latest.lock().unwrap_or_else(|p| p.into_inner());
        while !guard.as_ref().is_some_and(|s| s.converged) {
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                break;
            }
            guard = self
                .shared
                .changed
                .wait_timeout(guard, left)
                .unwrap_or_else(|p| p.into_inner())
                .0;
        }
        guard.clone()
    }

    /// (seconds, stats) after every shot so far.
    pub fn history(&self) -> Vec<(f64, Stats)> {
        self.shared
            .history
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .clone()
    }

    /// Whether two handles share one solve.
    pub fn same_solve(&self, other: &RadiosityHandle) -> bool {
        Arc::ptr_eq(&self.shared, &other.shared)
    }
}

fn publish(shared: &Shared, solver: &Solver, start: Instant, converged: bool) {
    let (direct, indirect) = solver.irradiance(true);
    let four = |v: Vec<glam::Vec3>| v.into_iter().map(|c| c.extend(0.0).to_array()).collect();
    let version = shared.version.load(Ordering::Acquire) + 1;
    let snapshot = Snapshot {
        version,
        direct: four(direct),
        indirect: four(indirect),
        stats: solver.stats(),
        elapsed_s: start.elapsed().as_secs_f64(),
        converged,
    };
    let mut guard = shared.latest.lock().unwrap_or_else(|p| p.into_inner());
    *guard = Some(Arc::new(snapshot));
    shared.version.store(version, Ordering::Release);
    if converged {
        shared.done.store(true, Ordering::Release);
    }
    shared.changed.notify_all();
}

fn run(mut solver: Solver, weak: Weak<Shared>, scene: &str) {
    let start = Instant::now();
    let mut last_publish = Instant::now();
    let mut last_log = Instant::now();
    // The first snapshot (ambient preview of the emitted light only) lets frames start lit.
    if let Some(shared) = weak.upgrade() {
        publish(&shared, &solver, start, false);
    }
    loop {
        let converged = solver.converged() || solver.step().is_none();
        let stats = solver.stats();
        let Some(shared) = weak.upgrade() else {
            tracing::info!(
                scene,
                shots = stats.shots,
                "radiosity no longer needed; stopped"
            );
            return;
        };
        shared
            .history
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .push((start.elapsed().as_secs_f64(), stats));
        metrics::gauge!("fovea_radiosity_unshot_fraction", "scene" => scene.to_string())
            .set(stats.unshot_fraction);
        if converged || last_publish.elapsed() >= SNAPSHOT_EVERY {
            publish(&shared, &solver, start, converged);
            last_publish = Instant::now();
        }
        if converged || last_log.elapsed() >= Duration::from_secs(1) {
            tracing::info!(
                scene,
                shots = stats.shots,
                elements = stats.elements,
                unshot_percent = format!("{:.2}", 100.0 * stats.unshot_fraction),
                seconds = format!("{:.1}", start.elapsed().as_secs_f64()),
                "radiosity {}",
                if converged { "converged" } else { "refining" }
            );
            last_log = Instant::now();
        }
        if converged {
            return;
        }
    }
}
