use glam::{Mat4, Vec3};
use serde::{Deserialize, Serialize};

/// A pinhole camera in scene units (1 unit = 1 cm unless the scene says otherwise).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    pub eye: [f32; 3],
    pub target: [f32; 3],
    #[serde(default = "up")]
    pub up: [f32; 3],
    pub fov_y_deg: f32,
    pub near: f32,
    pub far: f32,
}

fn up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

impl Camera {
    /// World → clip for a `width`×`height` frame: right-handed view, wgpu's 0..1 depth range.
    pub fn view_proj(&self, width: u32, height: u32) -> Mat4 {
        let aspect = width.max(1) as f32 / height.max(1) as f32;
        let view = Mat4::look_at_rh(self.eye.into(), self.target.into(), self.up.into());
        let proj = Mat4::perspective_rh(self.fov_y_deg.to_radians(), aspect, self.near, self.far);
        proj * view
    }

    pub fn validate(&self) -> Result<(), String> {
        let eye = Vec3::from(self.eye);
        let fwd = Vec3::from(self.target) - eye;
        if !(eye.is_finite() && fwd.is_finite() && Vec3::from(self.up).is_finite()) {
            return Err("camera vectors must be finite".into());
        }
        if fwd.length() < 1e-6 {
            return Err("camera eye and target coincide".into());
        }
        if fwd.normalize().cross(Vec3::from(self.up)).length() < 1e-6 {
            return Err("camera up is parallel to its view direction".into());
        }
        if !(self.fov_y_deg > 1.0 && self.fov_y_deg < 179.0) {
            return Err(format!("fov_y_deg {} is outside (1, 179)", self.fov_y_deg));
        }
        if !(self.near > 0.0 && self.far > self.near && self.far.is_finite()) {
            return Err(format!(
                "need 0 < near < far, got near {} far {}",
                self.near, self.far
            ));
        }
        Ok(())
    }
}
