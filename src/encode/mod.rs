//! Image encoding of read-back frames: JPEG for streaming, PNG when frames must compare
//! exactly, H.264 (per session, `h264`) when bytes matter.

pub mod foveated;
pub mod h264;
pub mod hold;
pub mod inset;
pub mod inset_packed;
pub mod picture;
pub mod rate_guard;
pub mod shown;
pub mod yuv;

use crate::protocol::Codec;

#[derive(Debug, thiserror::Error)]
pub enum EncodeError {
    #[error("{width}x{height} RGBA needs {expected} bytes, got {got}")]
    Size {
        width: u32,
        height: u32,
        expected: usize,
        got: usize,
    },
    #[error("JPEG frames are at most 65535 pixels per side, got {0}x{1}")]
    JpegTooLarge(u32, u32),
    #[error("JPEG encoding failed: {0}")]
    Jpeg(#[from] jpeg_encoder::EncodingError),
    #[error("PNG encoding failed: {0}")]
    Png(#[from] png::EncodingError),
    #[error("H.264 encoding failed: {0}")]
    H264(String),
    #[error("H.264 frames need an even width and height, got {0}x{1}")]
    OddSize(u32, u32),
    #[error("H.264 frames are encoded by the session's own stream, not one at a time")]
    NeedsStream,
}

/// Encodes tightly packed sRGB RGBA8 pixels. `quality` (1–100) applies to JPEG only.
pub fn encode(
    rgba: &[u8],
    width: u32,
    height: u32,
    codec: Codec,
    quality: u8,
) -> Result<Vec<u8>, EncodeError> {
    let expected = width as usize * height as usize * 4;
    if rgba.len() != expected {
        return Err(EncodeError::Size {
            width,
            height,
            expected,
            got: rgba.len(),
        });
    }
    match codec {
        Codec::Jpeg => encode_jpeg(rgba, width, height, quality),
        Codec::Png => encode_png(rgba, width, height),
        Codec::H264 => Err(EncodeError::NeedsStream),
    }
}

fn encode_jpeg(rgba: &[u8], width: u32, height: u32, quality: u8) -> Result<Vec<u8>, EncodeError> {
    let (Ok(w), Ok(h)) = (u16::try_from(width), u16::try_from(height)) else {
        return Err(EncodeError::JpegTooLarge(width, height));
    };
    let mut out = Vec::with_capacity(rgba.len() / 8);
    let encoder = jpeg_encoder::Encoder::new(&mut out, quality.clamp(1, 100));
    encoder.encode(rgba, w, h, jpeg_encoder::ColorType::Rgba)?;
    Ok(out)
}

fn encode_png(rgba: &[u8], width: u32, height: u32) -> Result<Vec<u8>, EncodeError> {
    let mut out = Vec::with_capacity(rgba.len() / 2);
    {
        let mut encoder = png::Encoder::new(&mut out, width, height);
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(png::BitDepth::Eight);
        // Frames are streamed: a fast deflate matters more than the last few percent of size.
        encoder.set_compression(png::Compression::Fast);
        let mut writer = encoder.write_header()?;
        writer.write_image_data(rgba)?;
        writer.finish()?;
    }
    Ok(out)
}

/// An opaque RGBA picture of xorshift noise: every byte value in every channel, reproducible
/// from `seed` (non-zero), for the encoders' unit tests.
#[cfg(test)]
pub(crate) fn noise_rgba(pixels: usize, mut seed: u32) -> Vec<u8> {
    (0..pixels * 4)
        .map(|i| {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            if i % 4 == 3 {
                255
            } else {
                (seed >> 24) as u8
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrong_buffer_length_is_an_error() {
        let e = encode(&[0; 10], 2, 2, Codec::Png, 90).unwrap_err();
        assert!(matches!(
            e,
            EncodeError::Size {
                expected: 16,
                got: 10,
                ..
            }
        ));
    }

    #[test]
    fn both_codecs_write_their_magic_bytes() {
        let px = vec![128u8; 8 * 8 * 4];
        let jpeg = encode(&px, 8, 8, Codec::Jpeg, 80).unwrap();
        assert_eq!(&jpeg[..2], &[0xFF, 0xD8]);
        let png = encode(&px, 8, 8, Codec::Png, 80).unwrap();
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    }
}
