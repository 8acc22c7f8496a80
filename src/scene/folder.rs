//! Scene folders: where files may be read from. A client names a scene, never a path, and a
//! scene file names its meshes relative to itself; every such path is resolved here and must
//! stay inside the folder the operator configured (no `..` escapes, no absolute paths, no
//! symlinks that lead out).

use std::path::{Component, Path, PathBuf};

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FolderError {
    #[error("{path:?}: {message}")]
    Refused { path: String, message: &'static str },
    #[error("{path:?} does not exist in {folder}")]
    Missing { path: String, folder: String },
    #[error("{path:?} leads outside {folder} (through a symlink or ..)")]
    Escapes { path: String, folder: String },
    #[error("scene folder {folder}: {message}")]
    Folder { folder: String, message: String },
}

/// A directory files may be read from, canonicalised once.
#[derive(Debug, Clone, PartialEq)]
pub struct Folder {
    root: PathBuf,
}

impl Folder {
    pub fn open(dir: &Path) -> Result<Folder, FolderError> {
        let root = dir.canonicalize().map_err(|e| FolderError::Folder {
            folder: dir.display().to_string(),
            message: e.to_string(),
        })?;
        if !root.is_dir() {
            return Err(FolderError::Folder {
                folder: dir.display().to_string(),
                message: "not a directory".into(),
            });
        }
        Ok(Folder { root })
    }

    pub fn root(&self) -> &Path {
        &self.root
    }

    /// `relative` (as written in a file that lives in `base`, itself inside the folder) as a
    /// real path inside the folder.
    pub fn resolve(&self, base: &Path, relative: &str) -> Result<PathBuf, FolderError> {
        let refuse = |message| FolderError::Refused {
            path: relative.to_string(),
            message,
        };
        if relative.is_empty() {
            return Err(refuse("empty path"));
        }
        if relative.contains("://") || relative.starts_with("data:") {
            return Err(refuse("URIs are not read; name a file beside the scene"));
        }
        let rel = Path::new(relative);
        if rel
            .components()
            .any(|c| matches!(c, Component::RootDir | Component::Prefix(_)))
        {
            return Err(refuse(
                "absolute paths are refused; use a path relative to the scene file",
            ));
        }
        let joined = base.join(rel);
        let real = joined.canonicalize().map_err(|_| FolderError::Missing {
            path: relative.to_string(),
            folder: self.root.display().to_string(),
        })?;
        if !real.starts_with(&self.root) {
            return Err(FolderError::Escapes {
                path: relative.to_string(),
                folder: self.root.display().to_string(),
            });
        }
        Ok(real)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_stay_inside_the_folder() {
        let dir = std::env::temp_dir().join(format!("fovea-folder-{}", std::process::id()));
        let inside = dir.join("scenes");
        std::fs::create_dir_all(inside.join("sub")).unwrap();
        std::fs::write(inside.join("sub/a.ply"), b"ply").unwrap();
        std::fs::write(dir.join("secret.ply"), b"ply").unwrap();
        let f = Folder::open(&inside).unwrap();
        let base = f.root().to_path_buf();
        assert!(f.resolve(&base, "sub/a.ply").is_ok());
        assert!(f.resolve(&base.join("sub"), "../sub/a.ply").is_ok());
        assert!(matches!(
            f.resolve(&base, "../secret.ply"),
            Err(FolderError::Escapes { .. })
        ));
        assert!(matches!(
            f.resolve(&base, "/etc/passwd"),
            Err(FolderError::Refused { .. })
        ));
        assert!(matches!(
            f.resolve(&base, "nothing.ply"),
            Err(FolderError::Missing { .. })
        ));
        assert!(f.resolve(&base, "http://example.com/a.bin").is_err());
        #[cfg(unix)]
        {
            let link = inside.join("link.ply");
            let _ = std::fs::remove_file(&link);
            std::os::unix::fs::symlink(dir.join("secret.ply"), &link).unwrap();
            assert!(matches!(
                f.resolve(&base, "link.ply"),
                Err(FolderError::Escapes { .. })
            ));
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
