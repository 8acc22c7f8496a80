use serde::{Deserialize, Serialize};

/// The limits a server enforces, sent to every client in `welcome` so nothing is a surprise.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Limits {
    /// Longest text message handled with an `error` reply; longer ones are rejected unread.
    pub max_message_bytes: usize,
    /// Frames larger than this are refused at `hello` (both dimensions also have to be ≥ 1).
    pub max_width: u32,
    pub max_height: u32,
    /// Upper bound for `hello.max_in_flight` (frames sent but not yet acknowledged).
    pub max_in_flight: u32,
    /// Valid pupil diameters in millimetres; physiological pupils are about 2–8 mm.
    pub pupil_mm: [f64; 2],
    /// Gaze coordinates are normalised to the frame, top-left origin, both in this closed range.
    pub gaze: [f64; 2],
    /// Longest a session's frame may take on the render thread, shared fairly among the
    /// sessions rendering (its own render time × sessions); a `hello` or `settings` past it is
    /// refused with `over_budget`.
    #[serde(default)]
    pub frame_budget_ms: f64,
    /// Longest piece of work another session's frame can wait behind: longer frames are
    /// rendered in parts of about this length, others' frames in between.
    #[serde(default)]
    pub slice_ms: f64,
    /// What the server's scene files may hold (`serve --scenes`; `docs/scenes.md`).
    #[serde(default)]
    pub scene_files: SceneFileLimits,
}

/// The limits every scene and model file is loaded under (`scene::limits`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SceneFileLimits {
    pub max_file_bytes: u64,
    pub max_vertices: usize,
    pub max_triangles: usize,
    pub max_texture_edge: u32,
    pub max_materials: usize,
    pub max_lights: usize,
}

impl Default for SceneFileLimits {
    fn default() -> Self {
        use crate::scene::limits as l;
        SceneFileLimits {
            max_file_bytes: l::MAX_FILE_BYTES,
            max_vertices: l::MAX_VERTICES,
            max_triangles: l::MAX_TRIANGLES,
            max_texture_edge: l::MAX_TEXTURE_EDGE,
            max_materials: crate::scene::MAX_MATERIALS,
            max_lights: crate::scene::MAX_LIGHTS,
        }
    }
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_message_bytes: 4096,
            max_width: 3840,
            max_height: 2160,
            max_in_flight: 8,
            pupil_mm: [1.0, 10.0],
            gaze: [0.0, 1.0],
            frame_budget_ms: 10_000.0,
            // The server states its renderer's (`render::SLICE_MS`).
            slice_ms: 0.0,
            scene_files: SceneFileLimits::default(),
        }
    }
}
