//! `fovea replay --save-frames`: every received frame written as the file it is. A JPEG or
//! PNG frame is one image (`NNNNNN.jpg` / `.png`, NNNNNN its frame number); an inset frame is
//! two (`NNNNNN-base.jpg`, the downscaled whole frame, and `NNNNNN-inset.jpg`; the header's
//! placement is in the session's frames, docs/protocol.md); H.264 frames are not images on
//! their own (each P-frame refers to the ones before it), so a connection's frames are
//! appended in order to one Annex B stream, `stream-C.h264` (C: the connection, 0 then one
//! more per reconnect), which FFmpeg reads as raw H.264 (`-f h264`). An inset session's
//! stream holds its packed pictures, base and inset side by side, as they were sent.

use std::io::Write;
use std::path::Path;

use super::replay::FrameRecord;
use crate::protocol::Codec;

/// Writes the kept images of `frames` into `dir` (created if missing); returns how many files
/// it wrote or appended to.
pub fn save_frames(dir: &Path, frames: &[FrameRecord]) -> std::io::Result<usize> {
    std::fs::create_dir_all(dir)?;
    let mut streams = std::collections::BTreeMap::new();
    let mut files = 0;
    for f in frames {
        let Some(image) = &f.image else { continue };
        let ext = match f.codec {
            Codec::Png => "png",
            Codec::Jpeg => "jpg",
            Codec::H264 => {
                let stream = match streams.entry(f.connection) {
                    std::collections::btree_map::Entry::Occupied(e) => e.into_mut(),
                    std::collections::btree_map::Entry::Vacant(e) => {
                        let name = format!("stream-{}.h264", f.connection);
                        files += 1;
                        e.insert(std::fs::File::create(dir.join(name))?)
                    }
                };
                stream.write_all(image)?;
                continue;
            }
        };
        match f.inset_bytes.filter(|n| *n <= image.len()) {
            Some(n) => {
                let (base, inset) = image.split_at(image.len() - n);
                std::fs::write(dir.join(format!("{:06}-base.{ext}", f.frame)), base)?;
                std::fs::write(dir.join(format!("{:06}-inset.{ext}", f.frame)), inset)?;
                files += 2;
            }
            None => {
                std::fs::write(dir.join(format!("{:06}.{ext}", f.frame)), image)?;
                files += 1;
            }
        }
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(frame: u64, connection: u32, codec: Codec, image: &[u8]) -> FrameRecord {
        FrameRecord {
            frame,
            connection,
            seq: None,
            sample_t_ms: None,
            sent_ms: None,
            received_ms: 0.0,
            latency_ms: None,
            gaze_x: 0.5,
            gaze_y: 0.5,
            queue_ms: 0.0,
            render_ms: 0.0,
            readback_ms: 0.0,
            encode_ms: 0.0,
            sampled: 1.0,
            bytes: image.len(),
            server_samples: 0,
            keyframe: None,
            image: Some(image.to_vec()),
            codec,
            inset_bytes: None,
        }
    }

    #[test]
    fn each_frame_is_saved_as_the_file_it_is() {
        let dir = std::env::temp_dir().join(format!("fovea-saved-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let inset = FrameRecord {
            inset_bytes: Some(2),
            ..record(3, 0, Codec::Jpeg, b"BASEin")
        };
        let frames = [
            record(1, 0, Codec::Jpeg, b"jpeg"),
            record(2, 0, Codec::Png, b"png"),
            inset,
            record(4, 0, Codec::H264, b"key"),
            record(5, 0, Codec::H264, b"+p"),
            // A reconnect starts a new stream (with its own keyframe).
            record(1, 1, Codec::H264, b"new"),
            FrameRecord {
                image: None,
                ..record(9, 0, Codec::Jpeg, b"x")
            },
        ];
        assert_eq!(save_frames(&dir, &frames).unwrap(), 6);
        let read = |name: &str| std::fs::read(dir.join(name)).unwrap();
        assert_eq!(read("000001.jpg"), b"jpeg");
        assert_eq!(read("000002.png"), b"png");
        assert_eq!(read("000003-base.jpg"), b"BASE");
        assert_eq!(read("000003-inset.jpg"), b"in");
        assert_eq!(read("stream-0.h264"), b"key+p");
        assert_eq!(read("stream-1.h264"), b"new");
        assert!(
            !dir.join("000009.jpg").exists(),
            "a frame without its image"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
