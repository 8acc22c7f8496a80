//! Tables the docs carry that the code generates: they must not drift.
//! Regenerate with `cargo run --release --example docs_tables`.

fn doc(path: &str) -> String {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(root.join(path)).unwrap()
}

#[test]
fn architecture_lists_the_passes_as_declared() {
    let table = fovea::render::frame::passes_markdown();
    assert!(
        doc("docs/architecture.md").contains(&table),
        "docs/architecture.md's pass table differs from the declarations; it should read:\n{table}"
    );
}

#[test]
fn protocol_lists_every_knob_as_declared() {
    let table = fovea::settings::knobs::markdown_table();
    assert!(
        doc("docs/protocol.md").contains(&table),
        "docs/protocol.md's knob table differs from settings/knobs.rs; it should read:\n{table}"
    );
}
