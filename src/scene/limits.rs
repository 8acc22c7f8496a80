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

/// Reads a file of at most `MAX_FILE_BYTES`.
pub fn read_limited(path: &std::path::Path) -> std::io::Result<Vec<u8>> {
    read_capped(path, MAX_FILE_BYTES)
}

/// Reads a file of at most `max` bytes. The cap holds while reading, not only against the
/// size the file system states: `/dev/zero`, a pipe or a file still growing says 0 or less.
pub fn read_capped(path: &std::path::Path, max: u64) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let too_big = |n: &dyn std::fmt::Display| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "{} is {n} bytes; files over {max} bytes are refused",
                path.display()
            ),
        )
    };
    let file = std::fs::File::open(path)?;
    let stated = file.metadata()?.len();
    if stated > max {
        return Err(too_big(&stated));
    }
    let mut bytes = Vec::with_capacity(stated as usize);
    file.take(max + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max {
        return Err(too_big(&format_args!("over {max}")));
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_cap_holds_for_files_that_do_not_say_their_size() {
        let zero = std::path::Path::new("/dev/zero");
        let e = super::read_capped(zero, 1 << 20).unwrap_err();
        assert!(e.to_string().contains("refused"), "{e}");
        let here = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("Cargo.toml");
        assert!(super::read_capped(&here, 1 << 20).is_ok());
        assert!(super::read_capped(&here, 10).is_err());
    }
}
