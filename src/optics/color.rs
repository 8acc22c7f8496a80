//! sRGB transfer functions (IEC 61966-2-1). The GPU applies the same curve when it writes to an
//! `*Srgb` texture, which is how frames leave the renderer.

/// Linear [0, 1] → sRGB-encoded [0, 1]. Out-of-range and NaN inputs clamp instead of propagating.
pub fn linear_to_srgb(c: f32) -> f32 {
    let c = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// sRGB-encoded [0, 1] → linear [0, 1].
pub fn srgb_to_linear(c: f32) -> f32 {
    let c = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
    if c <= 0.040_45 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

pub fn linear_to_srgb8(c: f32) -> u8 {
    (linear_to_srgb(c) * 255.0 + 0.5) as u8
}

pub fn srgb8_to_linear(c: u8) -> f32 {
    srgb_to_linear(f32::from(c) / 255.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_byte_survives_a_round_trip_through_linear() {
        for b in 0..=255u8 {
            assert_eq!(linear_to_srgb8(srgb8_to_linear(b)), b);
        }
    }

    #[test]
    fn extremes_clamp_instead_of_producing_garbage() {
        assert_eq!(linear_to_srgb8(f32::NAN), 0);
        assert_eq!(linear_to_srgb8(-1.0), 0);
        assert_eq!(linear_to_srgb8(f32::INFINITY), 255);
        assert_eq!(linear_to_srgb8(7.0), 255);
    }
}
