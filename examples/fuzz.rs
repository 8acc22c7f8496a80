//! The fuzz run: every target of `fuzz/targets.rs` (or those named), N inputs each, from the
//! committed corpus. Findings are written to `fuzz/findings/<target>-<n>.bin` to become
//! regression tests; the exit status is non-zero when there are any.
//!
//!   cargo run --release --example fuzz -- [--executions N] [--seed S] [TARGET…]

#[path = "../fuzz/engine.rs"]
mod engine;
#[path = "../fuzz/targets.rs"]
mod targets;
#[path = "../src/cli/target.rs"]
mod url_guard;

use std::path::Path;
use std::time::Instant;

#[global_allocator]
static ALLOC: engine::Counting = engine::Counting;

fn main() -> anyhow::Result<()> {
    let mut executions: u64 = 1_000_000;
    let mut seed: u64 = 1;
    let mut names = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut number = |what: &str| -> anyhow::Result<u64> {
            let v = args
                .next()
                .ok_or_else(|| anyhow::anyhow!("{what} needs a number"))?;
            Ok(v.parse()?)
        };
        match a.as_str() {
            "--executions" => executions = number("--executions")?,
            "--seed" => seed = number("--seed")?,
            "-h" | "--help" => {
                println!("fuzz [--executions N (default 10^6)] [--seed S] [TARGET…]");
                let all: Vec<&str> = targets::TARGETS.iter().map(|t| t.name).collect();
                println!("targets: {}", all.join(", "));
                return Ok(());
            }
            name => names.push(name.to_string()),
        }
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz");
    let mut found = 0;
    println!(
        "| target | inputs | accepted | time | slowest input | most allocated at once | findings |"
    );
    println!("|---|---|---|---|---|---|---|");
    for (i, target) in targets::TARGETS.iter().enumerate() {
        if !names.is_empty() && !names.iter().any(|n| n == target.name) {
            continue;
        }
        let corpus = engine::corpus(&root.join("corpus"), target.name);
        let began = Instant::now();
        let report = engine::fuzz(target, &corpus, executions, seed.wrapping_add(i as u64));
        println!(
            "| {} | {} | {:.1}% | {:.0} s | {:.1} ms | {} KiB | {} |",
            target.name,
            report.executions,
            100.0 * report.accepted as f64 / report.executions.max(1) as f64,
            began.elapsed().as_secs_f64(),
            report.slowest.as_secs_f64() * 1e3,
            report.peak_bytes >> 10,
            report.findings.len()
        );
        for (n, (finding, input)) in report.findings.iter().enumerate().take(20) {
            std::fs::create_dir_all(root.join("findings"))?;
            let file = root
                .join("findings")
                .join(format!("{}-{n}.bin", target.name));
            std::fs::write(&file, input)?;
            eprintln!("{}: {finding:?} → {}", target.name, file.display());
        }
        found += report.findings.len();
    }
    if found > 0 {
        anyhow::bail!("{found} findings");
    }
    Ok(())
}
