//! glTF buffers and image bytes: the GLB's BIN chunk, `data:` URIs, or files beside the glTF,
//! read only inside the scene folder and under the size limit.

use std::path::Path;

use super::GltfError;
use crate::scene::folder::Folder;
use crate::scene::limits::{read_limited, MAX_FILE_BYTES};

pub fn load_buffers(
    doc: &gltf::Document,
    blob: Option<Vec<u8>>,
    base: &Path,
    folder: Option<&Folder>,
) -> Result<Vec<Vec<u8>>, GltfError> {
    let mut blob = blob;
    let mut out = Vec::new();
    for b in doc.buffers() {
        let index = b.index();
        let err = |message: String| GltfError::Buffer { index, message };
        if b.length() as u64 > MAX_FILE_BYTES {
            return Err(err(format!(
                "{} bytes is over the {MAX_FILE_BYTES}-byte limit",
                b.length()
            )));
        }
        let data = match b.source() {
            gltf::buffer::Source::Bin => blob
                .take()
                .ok_or_else(|| err("the GLB has no BIN chunk".into()))?,
            gltf::buffer::Source::Uri(uri) => read_uri(uri, base, folder).map_err(err)?,
        };
        if data.len() < b.length() {
            return Err(err(format!(
                "holds {} bytes, the file says {}",
                data.len(),
                b.length()
            )));
        }
        out.push(data);
    }
    Ok(out)
}

/// A buffer or image URI: an embedded base64 `data:` URI, or a file beside the glTF.
pub fn read_uri(uri: &str, base: &Path, folder: Option<&Folder>) -> Result<Vec<u8>, String> {
    use base64::Engine;
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, payload) = rest
            .split_once(";base64,")
            .ok_or("data URI is not base64")?;
        if payload.len() as u64 > MAX_FILE_BYTES * 4 / 3 {
            return Err("data URI over the size limit".into());
        }
        return base64::engine::general_purpose::STANDARD
            .decode(payload)
            .map_err(|e| format!("data URI: {e}"));
    }
    let decoded = percent_decode(uri);
    // A built-in model has no folder: it must carry everything inside itself.
    let folder = folder.ok_or("a built-in model cannot refer to files")?;
    let path = folder.resolve(base, &decoded).map_err(|e| e.to_string())?;
    read_limited(&path).map_err(|e| e.to_string())
}

/// URIs in glTF are percent-encoded (`my%20mesh.bin`).
fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}
