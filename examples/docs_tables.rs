//! Prints the tables the docs carry that are generated from the code: the frame's passes with
//! what each reads and writes (docs/architecture.md) and the knob list (docs/protocol.md).
//! Tests fail when the docs drift from these.
//!
//! cargo run --release --example docs_tables

fn main() {
    println!("{}", fovea::render::frame::passes_markdown());
    println!("{}", fovea::settings::knobs::markdown_table());
}
