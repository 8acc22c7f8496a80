//! The scenes a server offers by name: the built-in ones, then every scene file (`.json`) and
//! glTF file (`.gltf`, `.glb`) at the top of each `--scenes` folder, named by file stem. A
//! client names a scene, never a path.

use std::path::PathBuf;

use super::folder::Folder;
use super::{builtin_names, Scene, SceneError};

#[derive(Debug, Clone, PartialEq)]
pub struct CatalogEntry {
    pub name: String,
    /// The file and its folder; `None` for a built-in scene.
    pub file: Option<(PathBuf, usize)>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Catalog {
    folders: Vec<Folder>,
    entries: Vec<CatalogEntry>,
}

impl Default for Catalog {
    fn default() -> Self {
        Catalog::builtin()
    }
}

const SCENE_EXTENSIONS: &[&str] = &["json", "gltf", "glb"];

impl Catalog {
    pub fn builtin() -> Catalog {
        Catalog {
            folders: Vec::new(),
            entries: builtin_names()
                .into_iter()
                .map(|n| CatalogEntry {
                    name: n.to_string(),
                    file: None,
                })
                .collect(),
        }
    }

    /// The built-in scenes plus those in `dirs`; two scenes of one name are an error.
    pub fn with_folders(dirs: &[PathBuf]) -> Result<Catalog, SceneError> {
        let mut c = Catalog::builtin();
        for dir in dirs {
            let folder = Folder::open(dir).map_err(|e| SceneError::File {
                path: dir.display().to_string(),
                message: e.to_string(),
            })?;
            let index = c.folders.len();
            let read = std::fs::read_dir(folder.root()).map_err(|e| SceneError::File {
                path: dir.display().to_string(),
                message: e.to_string(),
            })?;
            let mut found: Vec<PathBuf> = read
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| {
                    p.extension().and_then(|e| e.to_str()).is_some_and(|e| {
                        SCENE_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str())
                    })
                })
                .collect();
            found.sort();
            for path in found {
                let name = path
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default();
                if let Some(other) = c.entries.iter().find(|e| e.name == name) {
                    let was = other
                        .file
                        .as_ref()
                        .map_or("a built-in scene".to_string(), |(p, _)| {
                            p.display().to_string()
                        });
                    return Err(SceneError::File {
                        path: path.display().to_string(),
                        message: format!("scene name {name:?} is taken by {was}; rename one"),
                    });
                }
                c.entries.push(CatalogEntry {
                    name,
                    file: Some((path, index)),
                });
            }
            c.folders.push(folder);
        }
        Ok(c)
    }

    pub fn entries(&self) -> &[CatalogEntry] {
        &self.entries
    }

    pub fn names(&self) -> Vec<String> {
        self.entries.iter().map(|e| e.name.clone()).collect()
    }

    /// Loads a scene by the name clients use; the scene carries that name.
    pub fn load(&self, name: &str) -> Result<Scene, SceneError> {
        let entry = self
            .entries
            .iter()
            .find(|e| e.name == name)
            .ok_or_else(|| SceneError::Unknown(name.to_string()))?;
        match &entry.file {
            None => Scene::builtin(name),
            Some((path, folder)) => {
                let mut scene = Scene::load(path, &self.folders[*folder])?;
                scene.file.name = name.to_string();
                Ok(scene)
            }
        }
    }
}
