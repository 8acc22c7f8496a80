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

    /// Turns the eye around the target: `yaw_deg` about the world's up axis, `pitch_deg` about
    /// the camera's right axis, the elevation kept within ±89° so the view never lines up with
    /// `up` (which would make the view matrix degenerate).
    pub fn orbit(&self, yaw_deg: f32, pitch_deg: f32) -> Camera {
        let (eye, target, up) = self.vectors();
        let offset = eye - target;
        let r = offset.length();
        let up_n = up.normalize_or(Vec3::Y);
        let elevation = (offset.dot(up_n) / r).clamp(-1.0, 1.0).asin().to_degrees();
        let pitch = (elevation + pitch_deg).clamp(-89.0, 89.0) - elevation;
        let turned = glam::Quat::from_axis_angle(up_n, yaw_deg.to_radians()) * offset;
        let right = turned.cross(up_n).normalize_or(Vec3::X);
        let turned = glam::Quat::from_axis_angle(right, pitch.to_radians()) * turned;
        Camera {
            eye: (target + turned).into(),
            ..*self
        }
    }

    /// Slides eye and target together across the view: `dx`, `dy` in view heights at the
    /// target's distance (right and up positive).
    pub fn pan(&self, dx: f32, dy: f32) -> Camera {
        let (eye, target, up) = self.vectors();
        let fwd = (target - eye).normalize();
        let right = fwd.cross(up).normalize_or(Vec3::X);
        let cam_up = right.cross(fwd);
        let height = 2.0 * (eye - target).length() * (self.fov_y_deg.to_radians() * 0.5).tan();
        let shift = (right * dx + cam_up * dy) * height;
        Camera {
            eye: (eye + shift).into(),
            target: (target + shift).into(),
            ..*self
        }
    }

    /// Moves the eye towards (factor < 1) or away from (> 1) the target, never closer than
    /// twice the near plane.
    pub fn dolly(&self, factor: f32) -> Camera {
        let (eye, target, _) = self.vectors();
        let offset = eye - target;
        let distance = (offset.length() * factor).max(2.0 * self.near);
        Camera {
            eye: (target + offset.normalize() * distance).into(),
            ..*self
        }
    }

    fn vectors(&self) -> (Vec3, Vec3, Vec3) {
        (self.eye.into(), self.target.into(), self.up.into())
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

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> Camera {
        Camera {
            eye: [0.0, 0.0, 10.0],
            target: [0.0, 0.0, 0.0],
            up: [0.0, 1.0, 0.0],
            fov_y_deg: 40.0,
            near: 0.1,
            far: 100.0,
        }
    }

    #[test]
    fn orbiting_keeps_the_distance_and_stops_short_of_the_pole() {
        let c = cam().orbit(90.0, 0.0);
        assert!(
            (Vec3::from(c.eye) - Vec3::new(10.0, 0.0, 0.0)).length() < 1e-4,
            "{c:?}"
        );
        let top = cam().orbit(0.0, 500.0);
        let e = Vec3::from(top.eye);
        assert!((e.length() - 10.0).abs() < 1e-3);
        assert!(
            e.y / 10.0 < 89.5f32.to_radians().sin() && e.y > 9.9,
            "{e:?}"
        );
        assert!(top.validate().is_ok());
    }

    #[test]
    fn pan_moves_eye_and_target_together_and_dolly_stops_at_the_near_plane() {
        let p = cam().pan(0.5, 0.0);
        assert!(
            (Vec3::from(p.eye) - Vec3::from(p.target) - Vec3::new(0.0, 0.0, 10.0)).length() < 1e-4
        );
        assert!(p.target[0] > 3.0, "half a view height to the right: {p:?}");
        let close = cam().dolly(1e-6);
        assert!((Vec3::from(close.eye).length() - 0.2).abs() < 1e-5);
        assert!(cam().dolly(2.0).eye[2] > 19.9);
    }
}
