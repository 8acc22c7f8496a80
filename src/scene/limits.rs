//! What a mesh or scene file may hold. Every loader checks these before it allocates, so a
//! header that claims 10⁹ vertices is refused instead of exhausting memory. The same numbers
//! are in `docs/scenes.md` and in `welcome` (`protocol::Limits`).

/// Largest file (mesh, glTF, or one buffer of a glTF) read from disk.
pub const MAX_FILE_BYTES: u64 = 256 * 1024 * 1024;
/// Vertices in one scene, all meshes together.
pub const MAX_VERTICES: usize = 2_000_000;
/// Triangles in one scene, all meshes together.
pub const MAX_TRIANGLES: usize = 4_000_000;
/// Largest texture edge in pixels (a glTF image larger than this is refused).
pub const MAX_TEXTURE_EDGE: u32 = 8192;
/// Corners of one polygon (a PLY or OBJ face) before it is refused.
pub const MAX_POLYGON_CORNERS: usize = 256;

/// Reads a file after checking its size against `MAX_FILE_BYTES`.
pub fn read_limited(path: &std::path::Path) -> std::io::Result<Vec<u8>> {
    let len = std::fs::metadata(path)?.len();
    if len > MAX_FILE_BYTES {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "{} is {len} bytes; files over {MAX_FILE_BYTES} bytes are refused",
                path.display()
            ),
        ));
    }
    std::fs::read(path)
}
