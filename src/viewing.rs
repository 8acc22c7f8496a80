//! Viewing geometry, once for everyone: the physical display ([`Display`]: its width and the
//! eye's distance) and a frame shown on it ([`Viewing`]), which turn pixels into degrees of
//! visual angle: the pixel's angle, eccentricity, the frame's field of view and gaze in pixels.
//! A leaf module: render, protocol, gaze and quality all use it, and it uses none of them.
//!
//! Units: angles in degrees, display sizes in centimetres.

use serde::{Deserialize, Serialize};

/// Physical display geometry (design.md §5 defaults: a 53 cm wide display at 60 cm).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Display {
    pub width_cm: f64,
    pub distance_cm: f64,
}

impl Default for Display {
    fn default() -> Self {
        Self {
            width_cm: 53.0,
            distance_cm: 60.0,
        }
    }
}

/// Physical viewing geometry of the frame as the viewer sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Viewing {
    /// Frame size in pixels.
    pub width: u32,
    pub height: u32,
    /// Physical width of the displayed frame and the eye's distance from it (on its axis,
    /// through the frame centre).
    pub width_cm: f64,
    pub distance_cm: f64,
}

impl Viewing {
    fn cm_per_px(&self) -> f64 {
        self.width_cm / f64::from(self.width.max(1))
    }

    /// Point on the screen (cm, eye at the origin looking down +z) of pixel coordinates (x, y),
    /// where (0, 0) is the top-left corner of the frame.
    fn screen_point(&self, x: f64, y: f64) -> [f64; 3] {
        let s = self.cm_per_px();
        [
            (x - 0.5 * f64::from(self.width)) * s,
            (y - 0.5 * f64::from(self.height)) * s,
            self.distance_cm,
        ]
    }

    /// Angle between the gaze and a pixel as seen from the eye, in degrees. Uses atan2 of the
    /// cross and dot products: acos of the normalised dot loses all precision near e = 0.
    pub fn eccentricity_deg(&self, gaze_px: [f64; 2], px: [f64; 2]) -> f64 {
        let a = self.screen_point(gaze_px[0], gaze_px[1]);
        let b = self.screen_point(px[0], px[1]);
        let cross = [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ];
        let cross_len = (cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]).sqrt();
        let dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        cross_len.atan2(dot).to_degrees()
    }

    /// The angle one pixel subtends at the centre of the display: the finest detail the display
    /// can show, `w_min` of the thesis.
    pub fn pixel_angle_deg(&self) -> f64 {
        (2.0 * (0.5 * self.cm_per_px() / self.distance_cm).atan()).to_degrees()
    }

    /// The largest eccentricity any pixel of the frame has for this gaze (one of the corners).
    pub fn max_eccentricity_deg(&self, gaze_px: [f64; 2]) -> f64 {
        let (w, h) = (f64::from(self.width), f64::from(self.height));
        [[0.0, 0.0], [w, 0.0], [0.0, h], [w, h]]
            .iter()
            .map(|c| self.eccentricity_deg(gaze_px, *c))
            .fold(0.0, f64::max)
    }
}

impl Viewing {
    /// A frame of `width`×`height` pixels filling the display's width.
    pub fn new(display: Display, width: u32, height: u32) -> Viewing {
        Viewing {
            width,
            height,
            width_cm: display.width_cm,
            distance_cm: display.distance_cm,
        }
    }

    /// The frame's field of view, horizontal and vertical, degrees (through its centre).
    pub fn field_of_view_deg(&self) -> [f64; 2] {
        let aspect = f64::from(self.height) / f64::from(self.width.max(1));
        let full = |cm: f64| 2.0 * (0.5 * cm / self.distance_cm).atan().to_degrees();
        [full(self.width_cm), full(self.width_cm * aspect)]
    }

    /// A normalised position (top-left origin, [0, 1]²) in pixels.
    pub fn to_pixels(&self, p: [f64; 2]) -> [f64; 2] {
        [p[0] * f64::from(self.width), p[1] * f64::from(self.height)]
    }

    /// Angle in degrees between two normalised frame positions seen from the eye.
    pub fn angle_deg(&self, a: [f64; 2], b: [f64; 2]) -> f64 {
        self.eccentricity_deg(self.to_pixels(a), self.to_pixels(b))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn field_of_view_matches_the_display_at_its_distance() {
        let v = Viewing::new(Display::default(), 640, 480);
        let [h, vert] = v.field_of_view_deg();
        assert!((h - 2.0 * (26.5f64 / 60.0).atan().to_degrees()).abs() < 1e-12);
        assert!((vert - 2.0 * (26.5f64 * 0.75 / 60.0).atan().to_degrees()).abs() < 1e-12);
        // The horizontal field equals the angle between the frame's left and right edges.
        assert!((v.angle_deg([0.0, 0.5], [1.0, 0.5]) - h).abs() < 1e-9);
    }
}
