//! A session's camera: what a `camera` message does to it.

/// The camera after a `camera` message (see `protocol::CameraMove` for the order), or why not.
pub fn moved(
    base: crate::scene::Camera,
    current: crate::scene::Camera,
    m: &crate::protocol::CameraMove,
) -> Result<crate::scene::Camera, String> {
    let f = |v: [f64; 3]| v.map(|x| x as f32);
    let mut c = if m.reset { base } else { current };
    if let Some(p) = m.pose {
        c.eye = f(p.eye);
        c.target = f(p.target);
        c.up = p.up.map_or(c.up, f);
    }
    if let Some([yaw, pitch]) = m.orbit_deg {
        c = c.orbit(yaw as f32, pitch as f32);
    }
    if let Some([dx, dy]) = m.pan {
        c = c.pan(dx as f32, dy as f32);
    }
    if let Some(d) = m.dolly {
        c = c.dolly(d as f32);
    }
    c.validate().map_err(|e| format!("camera: {e}"))?;
    Ok(c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::{CameraMove, CameraPose};

    #[test]
    fn camera_moves_apply_in_order_and_a_degenerate_pose_is_refused() {
        let base = crate::scene::Scene::builtin("bunny").unwrap().file.camera;
        let turned = moved(
            base,
            base,
            &CameraMove {
                orbit_deg: Some([30.0, 0.0]),
                ..Default::default()
            },
        )
        .unwrap();
        assert_ne!(turned.eye, base.eye);
        assert_eq!(turned.target, base.target);
        let back = moved(
            base,
            turned,
            &CameraMove {
                reset: true,
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(back, base);
        let on_target = CameraMove {
            pose: Some(CameraPose {
                eye: [1.0, 2.0, 3.0],
                target: [1.0, 2.0, 3.0],
                up: None,
            }),
            ..Default::default()
        };
        assert!(moved(base, turned, &on_target)
            .unwrap_err()
            .contains("coincide"));
    }
}
