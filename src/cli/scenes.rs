//! Scenes the command line names by path (`render --scene-file`, `--model`).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

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
