//! A small mutation fuzzer that runs on stable Rust (cargo-fuzz needs nightly, which these
//! machines cannot download). Each target is a function over bytes; the engine starts from a
//! committed corpus (`fuzz/corpus/<target>/`) and the target's own seeds, mutates (bit flips,
//! byte edits, cut and paste within and between inputs, dictionary tokens, extreme numbers),
//! and runs each input once, recording what it must never do:
//!
//! - panic (a panic that escapes the target; the production code's own guards may catch some);
//! - take long (over `SLOW` for one input: a hang in the making);
//! - allocate without bound (over `ALLOC_LIMIT` at once, measured by the counting allocator the
//!   binary installs, see [`Counting`]).
//!
//! There is no coverage feedback; mutants are kept in a bounded pool at random so mutations
//! compound. Included with `#[path]` by `examples/fuzz.rs` and `tests/fuzz.rs`.

#![allow(dead_code)] // each includer uses a part

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// One input taking longer than this is reported as slow.
pub const SLOW: Duration = Duration::from_secs(2);
/// Bytes live at once above which an input is reported as allocating without bound.
pub const ALLOC_LIMIT: usize = 512 << 20;
/// Largest input the mutator makes.
const MAX_LEN: usize = 64 << 10;
/// Mutants kept to mutate further.
const POOL: usize = 512;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

/// The system allocator, counting live bytes and their peak (install with
/// `#[global_allocator]`).
pub struct Counting;

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            let now = LIVE.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
            PEAK.fetch_max(now, Ordering::Relaxed);
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
            let now = LIVE.fetch_add(new_size, Ordering::Relaxed) + new_size;
            PEAK.fetch_max(now, Ordering::Relaxed);
        }
        p
    }
}

pub struct Target {
    pub name: &'static str,
    /// Parses the input; true when it was accepted (how deep the mutants get).
    pub run: fn(&[u8]) -> bool,
    /// Tokens worth inserting (keywords, field names, delimiters).
    pub dictionary: &'static [&'static str],
    /// Inputs to start from besides the corpus folder.
    pub seeds: &'static [&'static str],
}

#[derive(Debug)]
pub enum Finding {
    Panic(String),
    Slow(Duration),
    Allocation(usize),
}

#[derive(Debug, Default)]
pub struct Report {
    pub executions: u64,
    /// Inputs the parser accepted.
    pub accepted: u64,
    pub findings: Vec<(Finding, Vec<u8>)>,
    pub slowest: Duration,
    pub peak_bytes: usize,
}

/// xorshift64*: reproducible from the seed, no dependency.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed.max(1))
    }
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Numbers at the edges: what parsers and the arithmetic after them get wrong.
const EXTREMES: &[&str] = &[
    "0",
    "-0",
    "-1",
    "1e308",
    "-1e308",
    "1e-320",
    "NaN",
    "inf",
    "-inf",
    "4294967295",
    "4294967296",
    "18446744073709551615",
    "18446744073709551616",
    "9007199254740993",
    "2147483648",
    "0.0000001",
    "99999999999999999999999999",
    "0x7f",
    "1e400",
];

/// A structural edit of a JSON input (most of our formats are JSON): one value somewhere in
/// the tree replaced by an extreme number, a string, null, an empty or deep container, another
/// value of the tree, or a key removed. Keeps the text parseable so the checks after parsing
/// (ranges, references, limits) are what gets exercised.
fn mutate_json(rng: &mut Rng, value: &mut serde_json::Value, dictionary: &[&str]) {
    use serde_json::Value;
    let node = pick(rng, value);
    let op = rng.below(9);
    if op == 8 {
        if let Value::Object(o) = node {
            if let Some(k) = o.keys().nth(rng.below(o.len().max(1))).cloned() {
                o.remove(&k);
            }
        }
        return;
    }
    let deep = (0..64).fold(Value::Null, |v, _| Value::Array(vec![v]));
    *node = match op {
        0 | 1 => {
            let t = EXTREMES[rng.below(EXTREMES.len())];
            serde_json::from_str(t).unwrap_or_else(|_| Value::String(t.into()))
        }
        2 => Value::from((rng.next() as i64) >> rng.below(64)),
        3 => Value::from(f64::from_bits(rng.next())),
        4 if !dictionary.is_empty() => Value::String(
            dictionary[rng.below(dictionary.len())]
                .trim_matches('"')
                .into(),
        ),
        5 => Value::Null,
        6 => [Value::Array(vec![]), Value::Object(Default::default())][rng.below(2)].clone(),
        _ => deep,
    };
}

/// A random node of the tree: each step down stops with probability 1/3.
fn pick<'a>(rng: &mut Rng, value: &'a mut serde_json::Value) -> &'a mut serde_json::Value {
    use serde_json::Value;
    let len = match &*value {
        Value::Array(a) => a.len(),
        Value::Object(o) => o.len(),
        _ => 0,
    };
    if len == 0 || rng.below(3) == 0 {
        return value;
    }
    let i = rng.below(len);
    match value {
        Value::Array(a) => pick(rng, &mut a[i]),
        Value::Object(o) => match o.values_mut().nth(i) {
            Some(v) => pick(rng, v),
            None => unreachable!("i < len"),
        },
        _ => unreachable!("only containers have children"),
    }
}

fn mutate(rng: &mut Rng, input: &[u8], other: &[u8], dictionary: &[&str]) -> Vec<u8> {
    if rng.below(2) == 0 {
        if let Ok(mut value) = serde_json::from_slice::<serde_json::Value>(input) {
            for _ in 0..1 + rng.below(3) {
                mutate_json(rng, &mut value, dictionary);
            }
            return serde_json::to_vec(&value).unwrap_or_default();
        }
    }
    let mut v = input.to_vec();
    for _ in 0..1 + rng.below(4) {
        let len = v.len();
        match rng.below(10) {
            0 if len > 0 => {
                let i = rng.below(len);
                v[i] ^= 1 << rng.below(8);
            }
            1 if len > 0 => {
                let i = rng.below(len);
                v[i] = rng.next() as u8;
            }
            2 => {
                let i = rng.below(len + 1);
                v.insert(i, rng.next() as u8);
            }
            3 if len > 0 => {
                let a = rng.below(len);
                let b = (a + 1 + rng.below(16)).min(len);
                v.drain(a..b);
            }
            4 if len > 0 => {
                let a = rng.below(len);
                let b = (a + 1 + rng.below(64)).min(len);
                let piece = v[a..b].to_vec();
                let at = rng.below(len + 1);
                v.splice(at..at, piece);
            }
            5 if !dictionary.is_empty() => {
                let t = dictionary[rng.below(dictionary.len())].as_bytes();
                let at = rng.below(len + 1);
                v.splice(at..at, t.iter().copied());
            }
            6 => {
                // Replace a run of digits (or insert) with an extreme number.
                let t = EXTREMES[rng.below(EXTREMES.len())].as_bytes();
                let start = rng.below(len + 1);
                let end = (start..len)
                    .find(|&i| !(v[i].is_ascii_digit() || v[i] == b'.' || v[i] == b'-'))
                    .unwrap_or(len);
                v.splice(start..end, t.iter().copied());
            }
            7 if !other.is_empty() => {
                // Splice: this input's head, the other's tail.
                let a = rng.below(len + 1);
                let b = rng.below(other.len());
                v.truncate(a);
                v.extend_from_slice(&other[b..]);
            }
            8 if len > 1 => v.truncate(rng.below(len)),
            _ => {
                let at = rng.below(len + 1);
                let b = [b'"', b'{', b'}', b'[', b']', b',', b':', b'\n', 0, 0xff][rng.below(10)];
                v.insert(at, b);
            }
        }
    }
    v.truncate(MAX_LEN);
    v
}

/// Runs `target` on each corpus entry, then on `executions` mutants in all.
pub fn fuzz(target: &Target, corpus: &[Vec<u8>], executions: u64, seed: u64) -> Report {
    let mut rng = Rng::new(seed);
    let mut base: Vec<Vec<u8>> = corpus.to_vec();
    base.extend(target.seeds.iter().map(|s| s.as_bytes().to_vec()));
    if base.is_empty() {
        base.push(Vec::new());
    }
    let mut pool: Vec<Vec<u8>> = Vec::new();
    let mut report = Report::default();
    // Panics are findings, not noise on stderr.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    for n in 0..executions {
        let input = if (n as usize) < base.len() {
            base[n as usize].clone()
        } else {
            let from = if !pool.is_empty() && rng.below(2) == 0 {
                &pool[rng.below(pool.len())]
            } else {
                &base[rng.below(base.len())]
            };
            let other = &base[rng.below(base.len())];
            mutate(&mut rng, from, other, target.dictionary)
        };
        let before = LIVE.load(Ordering::Relaxed);
        PEAK.store(before, Ordering::Relaxed);
        let began = Instant::now();
        let outcome = std::panic::catch_unwind(|| (target.run)(&input));
        let took = began.elapsed();
        let grew = PEAK.load(Ordering::Relaxed).saturating_sub(before);
        report.executions += 1;
        report.slowest = report.slowest.max(took);
        report.peak_bytes = report.peak_bytes.max(grew);
        if outcome.as_ref().is_ok_and(|ok| *ok) {
            report.accepted += 1;
        }
        if let Err(p) = outcome {
            let what = p
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            report.findings.push((Finding::Panic(what), input.clone()));
        } else if took > SLOW {
            report.findings.push((Finding::Slow(took), input.clone()));
        } else if grew > ALLOC_LIMIT {
            report
                .findings
                .push((Finding::Allocation(grew), input.clone()));
        }
        if pool.len() < POOL {
            pool.push(input);
        } else if rng.below(8) == 0 {
            let i = rng.below(POOL);
            pool[i] = input;
        }
    }
    std::panic::set_hook(hook);
    report
}

/// The committed corpus of `target`: every file in `dir/<target>/`.
pub fn corpus(dir: &std::path::Path, target: &str) -> Vec<Vec<u8>> {
    let mut files: Vec<_> = std::fs::read_dir(dir.join(target))
        .map(|d| d.flatten().map(|e| e.path()).collect())
        .unwrap_or_default();
    files.sort();
    files.iter().filter_map(|p| std::fs::read(p).ok()).collect()
}
