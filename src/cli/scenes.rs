//! Scenes the command line names by path (`render --scene-file`, `--model`).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use fovea::render::cost::{measure_foveation, WORTH_SAVING};
use fovea::render::{FrameRequest, Renderer};

/// Frames timed each way by `render --explain --measure`, interleaved, after one each that
/// builds pipelines.
const MEASURED_FRAMES: u32 = 5;

/// A scene file or model from the command line, confined to the folder it is in.
pub fn load_own_scene(path: &Path) -> Result<fovea::scene::Scene> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let folder = fovea::scene::Folder::open(&dir)?;
    let scene = fovea::scene::Scene::load(path, &folder)
        .with_context(|| format!("loading {}", path.display()))?;
    for note in &scene.notes {
        eprintln!("note: {note}");
    }
    Ok(scene)
}

/// The plan's foveation line: whether the preset foveates, and whether foveating this scene at
/// this size pays on this adapter (measured when `measure`), which is what the server decides
/// frame by frame.
pub fn explain_foveation(
    request: FrameRequest,
    own: Option<fovea::scene::Scene>,
    measure: bool,
) -> Result<()> {
    let (w, h) = (request.width, request.height);
    if !request.settings.foveation.enabled {
        println!("  foveation: off (this preset shades every pixel)");
        return Ok(());
    }
    let under = WORTH_SAVING * 100.0;
    if !measure {
        println!(
            "  foveation: on, unless the server's adapter measures it saving under {under:.0}% \
             of the whole frame here: then frames are shaded whole (--measure measures it here)"
        );
        return Ok(());
    }
    let mut renderer = Renderer::new().context("opening the GPU")?;
    if let Some(scene) = own {
        renderer.add_scene(scene)?;
    }
    eprintln!(
        "measuring on {}: {MEASURED_FRAMES} frames each way at {w}x{h}…",
        renderer.adapter()
    );
    let v = measure_foveation(&mut renderer, &request, MEASURED_FRAMES)?;
    if v.pays() {
        let gain = v.whole_ms / v.foveated_ms;
        println!("  foveation: pays on this adapter at {w}x{h}: {v} ({gain:.2}x cheaper)");
    } else {
        println!(
            "  foveation: does not pay on this adapter at {w}x{h}: {v}, a saving under \
             {under:.0}%; the server shades these frames whole (each frame's `unfoveated` says so)"
        );
    }
    Ok(())
}
