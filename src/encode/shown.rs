//! What a client of an H.264 stream shows, for the hold (`encode::hold`): the stream decoded
//! by openh264's decoder on a thread of its own.
//!
//! The hold needs frame N as decoded before it encodes frame N + 1, and decoding costs about
//! 3 ms a 720p frame, as much as the encode. Between the two the server renders frame N + 1
//! (tens of ms), so the decode runs then, on its own thread, and the next encode only waits
//! for what is left of it: the encoder thread's time per frame stays the encode's. The CPU
//! time is the same; it moves off the frame's path.

use std::sync::mpsc;

use openh264::formats::YUVSource;

use super::picture::I420;

/// A frame to decode, and the buffer the last picture came in (reused for this one).
struct Job {
    bytes: Vec<u8>,
    buffer: Option<I420>,
}

/// One stream's decoder thread and the picture it last decoded. Dropping it ends the thread
/// once its frame in hand is done.
pub struct Shown {
    jobs: mpsc::Sender<Job>,
    done: mpsc::Receiver<Option<I420>>,
    /// A frame sent that has not come back yet.
    pending: bool,
    picture: Option<I420>,
    /// The decoder failed (or never started): nothing is shown until a new `Shown`.
    failed: bool,
}

impl Shown {
    /// A decoder thread for a stream whose next frame is a keyframe (a decoder starts at one).
    pub fn start() -> Shown {
        let (jobs, inbox) = mpsc::channel::<Job>();
        let (outbox, done) = mpsc::channel();
        let spawned = std::thread::Builder::new()
            .name("fovea-h264-shown".into())
            .spawn(move || decode_loop(inbox, outbox));
        if let Err(e) = &spawned {
            tracing::warn!(error = %e, "no decoder thread for the periphery's hold; holding nothing");
        }
        Shown {
            jobs,
            done,
            pending: false,
            picture: None,
            failed: spawned.is_err(),
        }
    }

    /// Decodes `bytes`, the stream's next frame, in the background.
    pub fn submit(&mut self, bytes: Vec<u8>) {
        if self.failed {
            return;
        }
        // The previous frame's answer first: the decoder takes frames in order, one at a time.
        self.wait();
        let job = Job {
            bytes,
            buffer: self.picture.take(),
        };
        if self.jobs.send(job).is_ok() {
            self.pending = true;
        } else {
            self.failed = true;
        }
    }

    /// The last frame submitted, as decoded (waiting for it if need be); none if the decoder
    /// failed, which stops the hold until the next keyframe's `Shown`.
    pub fn picture(&mut self) -> Option<&I420> {
        self.wait();
        self.picture.as_ref().filter(|_| !self.failed)
    }

    fn wait(&mut self) {
        if !self.pending {
            return;
        }
        self.pending = false;
        match self.done.recv() {
            Ok(Some(picture)) => self.picture = Some(picture),
            // The stream did not decode, or the thread is gone.
            Ok(None) | Err(_) => {
                self.picture = None;
                self.failed = true;
            }
        }
    }
}

/// The decoder thread: a frame in, its picture (or `None`, after which it stops) out.
fn decode_loop(inbox: mpsc::Receiver<Job>, outbox: mpsc::Sender<Option<I420>>) {
    let decoder = super::h264::api().and_then(|api| {
        openh264::decoder::Decoder::with_api_config(api, Default::default())
            .map_err(|e| super::EncodeError::H264(e.to_string()))
    });
    let mut decoder = match decoder {
        Ok(d) => d,
        Err(e) => {
            tracing::warn!(error = %e, "no decoder for the periphery's hold; holding nothing");
            let _ = outbox.send(None);
            return;
        }
    };
    while let Ok(Job { bytes, buffer }) = inbox.recv() {
        let picture = match decoder.decode(&bytes) {
            Ok(Some(pic)) => {
                let (w, h) = pic.dimensions();
                let mut buffer = buffer
                    .filter(|b| b.dimensions() == (w, h))
                    .unwrap_or_else(|| I420::new(w, h));
                buffer.copy_from_source(&pic);
                Some(buffer)
            }
            // Our own stream failed to decode: hold nothing until the next keyframe.
            Ok(None) | Err(_) => None,
        };
        let failed = picture.is_none();
        if outbox.send(picture).is_err() || failed {
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::encode::h264::{H264Config, H264Stream};

    /// A 32×32 grey ramp's first frames from a stream of our own.
    fn frames(n: u64) -> Vec<Vec<u8>> {
        let rgba: Vec<u8> = (0..32 * 32).flat_map(|i| [(i % 32 * 8) as u8; 4]).collect();
        let mut stream = H264Stream::new(H264Config::default());
        (0..n)
            .map(|k| stream.encode_at(&rgba, 32, 32, k * 16).unwrap().bytes)
            .collect()
    }

    #[test]
    fn each_frame_comes_back_decoded_in_order() {
        let mut shown = Shown::start();
        for bytes in frames(3) {
            shown.submit(bytes);
            let picture = shown.picture().expect("our own stream decodes");
            assert_eq!(picture.dimensions(), (32, 32));
            // The ramp's luma: dark at the left edge, bright at the right.
            let row = &picture.y()[..32];
            assert!(row[0] < 20 && row[31] > 230, "{row:?}");
        }
    }

    #[test]
    fn a_frame_that_does_not_decode_stops_the_hold() {
        let mut shown = Shown::start();
        shown.submit(vec![0, 0, 0, 1, 0x65, 0xff, 0xff]);
        assert!(shown.picture().is_none());
        // Nothing more is decoded until a new `Shown` (the next keyframe).
        shown.submit(frames(1).remove(0));
        assert!(shown.picture().is_none());
    }
}
