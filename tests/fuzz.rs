//! Every parser that takes outside bytes survives a bounded fuzz run: 10⁴ inputs per target
//! (the committed corpus, then mutants), none of which may panic, run long or allocate without
//! bound. `scripts/fuzz.sh` runs the same targets for 10⁶ inputs each.

#[path = "../fuzz/engine.rs"]
mod engine;
#[path = "../fuzz/targets.rs"]
mod targets;
#[path = "../src/cli/target.rs"]
mod url_guard;

#[global_allocator]
static ALLOC: engine::Counting = engine::Counting;

const EXECUTIONS: u64 = 10_000;

/// The allocation count is process-wide: the two tests take turns.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

#[test]
fn no_parser_panics_hangs_or_runs_away_with_memory() {
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus");
    let mut failures = Vec::new();
    for (i, target) in targets::TARGETS.iter().enumerate() {
        let corpus = engine::corpus(&dir, target.name);
        assert!(
            !corpus.is_empty() || !target.seeds.is_empty(),
            "{} has no corpus",
            target.name
        );
        let report = engine::fuzz(target, &corpus, EXECUTIONS, 0x5eed + i as u64);
        eprintln!(
            "{}: {} inputs ({} accepted), slowest {:?}, most allocated at once {} KiB, {} findings",
            target.name,
            report.executions,
            report.accepted,
            report.slowest,
            report.peak_bytes >> 10,
            report.findings.len()
        );
        assert_eq!(report.executions, EXECUTIONS);
        // The corpus parses: mutants start from inputs that reach past the first check.
        assert!(report.accepted > 0, "{}: nothing was accepted", target.name);
        for (finding, input) in report.findings.iter().take(3) {
            failures.push(format!(
                "{}: {finding:?} on {:?}",
                target.name,
                String::from_utf8_lossy(input)
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The engine itself finds what it is for: a panic reached only by mutation, and an input
/// that allocates far more than it is long.
#[test]
fn the_engine_finds_a_planted_panic_and_a_runaway_allocation() {
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let planted = engine::Target {
        name: "planted",
        run: |b| {
            if b.windows(2).any(|w| w == b"}{") {
                panic!("planted");
            }
            if b.len() > 3 && b[0] == b'[' && b[b.len() - 1] == b'0' {
                let big = vec![1u8; engine::ALLOC_LIMIT + 1];
                std::hint::black_box(&big);
            }
            true
        },
        dictionary: &[],
        seeds: &["[1,2,3]", "{\"a\":1}"],
    };
    let report = engine::fuzz(&planted, &[], 3_000, 7);
    let panics = report
        .findings
        .iter()
        .filter(|(f, _)| matches!(f, engine::Finding::Panic(m) if m == "planted"))
        .count();
    let allocations = report
        .findings
        .iter()
        .filter(|(f, _)| matches!(f, engine::Finding::Allocation(_)))
        .count();
    assert!(
        panics > 0 && allocations > 0,
        "{panics} panics, {allocations} allocations"
    );
}
