//! H.264 frames: a rendered frame survives encode → decode (openh264's own decoder), keyframes
//! come when asked and when due, and a session streams them with the header saying which are
//! keyframes; bad requests get errors and the server lives; a target that pays for it
//! refines a still picture further.

use std::time::Duration;

use fovea::client::{Client, Event};
use fovea::encode::h264::{H264Config, H264Stream};
use fovea::protocol::{Ack, Codec, ErrorCode, Gaze, Hello};
use fovea::render::{FrameRequest, Renderer};
use openh264::decoder::Decoder;

mod common;

fn psnr(a: &[u8], b: &[u8]) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for (pa, pb) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
        for c in 0..3 {
            sum += (f64::from(pa[c]) - f64::from(pb[c])).powi(2);
            n += 1;
        }
    }
    10.0 * (255.0f64.powi(2) / (sum / n as f64)).log10()
}

fn decode(decoder: &mut Decoder, bytes: &[u8]) -> Vec<u8> {
    let yuv = decoder
        .decode(bytes)
        .expect("decodes")
        .expect("a picture per frame: nothing is held back");
    // Full range, as the stream's VUI says (openh264's own `write_rgba8` assumes limited).
    fovea::encode::yuv::picture_to_rgba(&yuv)
}

#[test]
fn a_rendered_frame_round_trips_above_35_db_and_keyframes_come_when_asked() {
    let mut renderer = Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"));
    let (w, h) = (320, 240);
    let mut frames = Vec::new();
    for x in [0.3, 0.35, 0.4, 0.45] {
        let mut req = FrameRequest::new("bunny", w, h);
        req.gaze = [x, 0.5];
        frames.push(renderer.render(&req).unwrap().rgba);
    }
    let mut stream = H264Stream::new(H264Config {
        kbps: 2000,
        keyframe_every: Duration::from_secs(3600),
    });
    let mut decoder = Decoder::new().unwrap();
    let mut keys = Vec::new();
    for (i, rgba) in frames.iter().enumerate() {
        if i == 3 {
            stream.ask_keyframe();
        }
        let f = stream.encode(rgba, w, h).unwrap();
        keys.push(f.keyframe);
        let back = decode(&mut decoder, &f.bytes);
        let db = psnr(rgba, &back);
        assert!(db >= 35.0, "frame {i}: {db:.1} dB");
    }
    assert_eq!(
        keys,
        [true, false, false, true],
        "first frame and the asked one"
    );
    // A size change starts over with a keyframe; odd sizes are refused, not a panic.
    let small: Vec<u8> = frames[0].iter().copied().take(160 * 120 * 4).collect();
    assert!(stream.encode(&small, 160, 120).unwrap().keyframe);
    assert!(stream.encode(&small[..159 * 120 * 4], 159, 120).is_err());
    // Keyframes when due: every frame with a zero interval.
    let mut every = H264Stream::new(H264Config {
        kbps: 2000,
        keyframe_every: Duration::ZERO,
    });
    assert!((0..3).all(|_| every.encode(&frames[0], w, h).unwrap().keyframe));
}

async fn next_frame(c: &mut Client) -> fovea::protocol::FrameHeader {
    loop {
        match c.next_event(Duration::from_secs(60)).await {
            Ok(Event::Frame { header, image }) => {
                assert_eq!(
                    header.bytes,
                    image.len(),
                    "the header says the image's size"
                );
                let ack = Ack {
                    frame: header.frame,
                    t_ms: None,
                    dropped: false,
                };
                c.ack(&ack).await.unwrap();
                return header;
            }
            Ok(Event::Error(e)) => panic!("error {e:?}"),
            Ok(_) => continue,
            Err(e) => panic!("no frame: {e}"),
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_h264_session_streams_keyframes_on_request_and_bad_requests_are_told() {
    let (addr, running) = common::start(Default::default()).await;
    let url = format!("ws://{addr}/ws");
    let hello = Hello {
        scene: "bunny".into(),
        width: 96,
        height: 64,
        preset: "fast".into(),
        codec: Codec::H264,
        bitrate_kbps: Some(500),
        ..Hello::default()
    };
    let mut c = Client::connect(&url).await.unwrap();
    let welcome = c.hello(&hello).await.unwrap();
    assert_eq!(welcome.codec, Codec::H264);
    let first = next_frame(&mut c).await;
    assert_eq!((first.codec, first.keyframe), (Codec::H264, Some(true)));
    let gaze = |seq: u64| Gaze {
        seq,
        t_ms: seq as f64,
        x: 0.3 + 0.05 * seq as f64,
        y: 0.5,
        pupil_mm: None,
        sample_t_ms: None,
    };
    c.gaze(&gaze(1)).await.unwrap();
    assert_eq!(next_frame(&mut c).await.keyframe, Some(false));
    c.send_text(r#"{"type":"keyframe"}"#).await.unwrap();
    assert_eq!(next_frame(&mut c).await.keyframe, Some(true), "asked for");
    c.gaze(&gaze(2)).await.unwrap();
    assert_eq!(next_frame(&mut c).await.keyframe, Some(false));

    // An odd size and an unknown codec are refused with a reason; the server goes on.
    let mut odd = Client::connect(&url).await.unwrap();
    let refused = odd
        .hello(&Hello {
            width: 95,
            ..hello.clone()
        })
        .await
        .unwrap_err();
    assert!(refused.to_string().contains("even"), "{refused}");
    let mut unknown = Client::connect(&url).await.unwrap();
    unknown
        .send_text(r#"{"type":"hello","codec":"vp9","width":96,"height":64}"#)
        .await
        .unwrap();
    match unknown.next_event(Duration::from_secs(10)).await {
        Ok(Event::Error(e)) => {
            assert_eq!(e.code, ErrorCode::BadField);
            assert!(e.message.contains("vp9"), "{}", e.message);
        }
        other => panic!("expected an error, got {other:?}"),
    }
    c.gaze(&gaze(3)).await.unwrap();
    assert_eq!(
        next_frame(&mut c).await.codec,
        Codec::H264,
        "the first session goes on"
    );
    running.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_foveated_h264_session_holds_its_periphery_and_every_frame_decodes() {
    let (addr, running) = common::start(Default::default()).await;
    let url = format!("ws://{addr}/ws");
    for inset_deg in [None, Some(16.0)] {
        let hello = Hello {
            scene: "gallery".into(),
            width: 320,
            height: 192,
            preset: "fast".into(),
            codec: Codec::H264,
            bitrate_kbps: Some(2000),
            foveated_encoding: true,
            inset_deg,
            ..Hello::default()
        };
        let mut c = Client::connect(&url).await.unwrap();
        c.hello(&hello).await.unwrap();
        let mut decoder = Decoder::new().unwrap();
        for seq in 0..6u64 {
            if seq > 0 {
                let gaze = Gaze {
                    seq,
                    t_ms: seq as f64,
                    x: 0.4,
                    y: 0.5,
                    pupil_mm: None,
                    sample_t_ms: None,
                };
                c.gaze(&gaze).await.unwrap();
            }
            let (header, image) = loop {
                match c.next_event(Duration::from_secs(60)).await {
                    Ok(Event::Frame { header, image }) => break (header, image),
                    Ok(Event::Error(e)) => panic!("error {e:?}"),
                    Ok(_) => continue,
                    Err(e) => panic!("no frame: {e}"),
                }
            };
            let ack = Ack {
                frame: header.frame,
                t_ms: None,
                dropped: false,
            };
            c.ack(&ack).await.unwrap();
            assert_eq!(header.keyframe, Some(seq == 0), "inset {inset_deg:?}");
            let pic = decoder.decode(&image).expect("decodes").expect("a picture");
            let (w, h) = openh264::formats::YUVSource::dimensions(&pic);
            assert!(w >= 320 || inset_deg.is_some(), "{w}x{h}");
        }
    }
    running.stop().await;
}

/// A 320×240 grey picture of fine detail, zoomed in by `step` percent: a camera moving in,
/// which motion compensation cannot follow as it follows a pan.
fn pattern(step: u64) -> Vec<u8> {
    let (w, h) = (320usize, 240usize);
    let zoom = 1.0 + 0.01 * step as f64;
    let mut out = Vec::with_capacity(w * h * 4);
    for y in 0..h {
        for x in 0..w {
            let u = (x as f64 - 160.0) / zoom;
            let v = (y as f64 - 120.0) / zoom;
            let a = 0.5 + 0.25 * (u * 0.9).sin() * (v * 0.7).cos() + 0.25 * ((u + v) * 0.31).sin();
            let c = (a * 255.0).round() as u8;
            out.extend_from_slice(&[c, c, c, 255]);
        }
    }
    out
}

/// A still picture keeps the fine quantiser (no keyframe after the first); a moving one that
/// overruns the target at it switches once, with a keyframe the decoder takes, and then holds
/// the target.
#[test]
fn a_moving_picture_frees_the_quantiser_to_hold_the_bitrate() {
    let kbps = 300;
    let run = |moving: bool| {
        let mut stream = H264Stream::new(H264Config {
            kbps,
            keyframe_every: Duration::from_secs(3600),
        });
        let mut decoder = Decoder::new().unwrap();
        let mut frames = Vec::new();
        for k in 0..60u64 {
            let rgba = pattern(if moving { k } else { 0 });
            let f = stream.encode_at(&rgba, 320, 240, k * 1000 / 60).unwrap();
            let back = decode(&mut decoder, &f.bytes);
            frames.push((f.keyframe, f.bytes.len(), psnr(&rgba, &back)));
        }
        frames
    };
    let still = run(false);
    assert!(still[0].0 && still[1..].iter().all(|f| !f.0), "{still:?}");
    let moving = run(true);
    let keys: Vec<usize> = (0..60).filter(|&k| moving[k].0).collect();
    assert_eq!(keys.len(), 2, "the first frame and one switch: {keys:?}");
    assert!(keys[1] > fovea::encode::rate_guard::WINDOW, "{keys:?}");
    // The P-frames after the switch come at about the target (a still stream's rate control
    // may run a little over: no frame is skipped): kbit/s = bytes per 1/60 s × 60 × 8 / 1000.
    let after = &moving[keys[1] + 1..];
    let rate = after.iter().map(|f| f.1 as f64).sum::<f64>() / after.len() as f64 * 0.48;
    assert!(rate < 1.5 * kbps as f64, "{rate:.0} kbit/s for {kbps}");
    let before = &moving[1..keys[1]];
    let over = before.iter().map(|f| f.1 as f64).sum::<f64>() / before.len() as f64 * 0.48;
    assert!(
        over > 2.0 * kbps as f64,
        "{over:.0} kbit/s before the switch"
    );
    // Every frame decoded, across the new encoder's parameter sets.
    assert!(moving.iter().all(|f| f.2 > 20.0), "{moving:?}");
}

/// Keyframes by the stream's clock: a still picture gets one every `keyframe_every` and none
/// between (the guard's checks cost nothing while it keeps its range); a camera move frees
/// the quantiser with one, and the first check after the picture is still again restores the
/// fine range with another.
#[test]
fn keyframes_come_at_the_period_and_where_the_range_switches_and_nowhere_else() {
    use fovea::encode::h264::GUARD_CHECK_MS;
    // `zoom(k)`: frame k's picture; frames 1/30 s apart from 1 s (so 10 s on is a frame).
    let keys_of = |zoom: &dyn Fn(u64) -> u64, frames: u64| {
        let mut stream = H264Stream::new(H264Config {
            kbps: 300,
            keyframe_every: Duration::from_secs(10),
        });
        let mut decoder = Decoder::new().unwrap();
        let mut keys = Vec::new();
        for k in 0..frames {
            let ms = 1000 + k * 100 / 3;
            let rgba = pattern(zoom(k));
            let f = stream.encode_at(&rgba, 320, 240, ms).unwrap();
            let back = decode(&mut decoder, &f.bytes);
            assert!(psnr(&rgba, &back) > 20.0, "frame {k}");
            if f.keyframe {
                keys.push(ms - 1000);
            }
        }
        keys
    };
    // Still for 25 s: at 0, 10 and 20 s only.
    let still = keys_of(&|_| 0, 750);
    assert_eq!(still, [0, 10_000, 20_000], "still");
    // Zooming in from 1 s to 1.6 s, still after: the guard frees the quantiser with a keyframe
    // and is back at the first check (every GUARD_CHECK_MS from the first frame), the picture
    // having been still for six P-frames by then.
    let moving = keys_of(&|k| k.clamp(30, 48) - 30, 180);
    assert_eq!(
        moving.len(),
        3,
        "the first, to the target, back: {moving:?}"
    );
    assert!(moving[1] > 1000 && moving[1] < 1600, "{moving:?}");
    assert_eq!(moving[2], GUARD_CHECK_MS, "{moving:?}");
}

/// One frame of `scene` rendered with the gaze at the centre.
fn still(scene: &str, w: u32, h: u32) -> Vec<u8> {
    let mut renderer = Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"));
    renderer
        .render(&FrameRequest::new(scene, w, h))
        .unwrap()
        .rgba
}

#[test]
fn a_held_periphery_stops_recoding_a_still_picture() {
    // openh264 below QP 18 re-codes a still picture in every P-frame (src/encode/h264.rs);
    // with the periphery held, only the blocks near the gaze are re-coded.
    let (w, h) = (640, 360);
    let rgba = still("gallery", w, h);
    let viewing = fovea::viewing::Viewing::new(Default::default(), w, h);
    let hold = fovea::encode::hold::Hold::default();
    let config = H264Config {
        kbps: 4000,
        keyframe_every: Duration::from_secs(3600),
    };
    let mut last = Vec::new();
    for held in [false, true] {
        let mut stream = H264Stream::new(config);
        let mut decoder = Decoder::new().unwrap();
        let mut bytes = 0;
        for k in 0..40u64 {
            if held {
                let t = fovea::encode::hold::thresholds(w, h, [0.5, 0.5], &viewing, &hold);
                stream.hold_next(t);
            }
            let f = stream.encode_at(&rgba, w, h, k * 16).unwrap();
            assert_eq!(f.keyframe, k == 0);
            let back = decode(&mut decoder, &f.bytes);
            if k >= 30 {
                bytes += f.bytes.len();
                let db = psnr(&rgba, &back);
                assert!(db >= 35.0, "held {held}, frame {k}: {db:.1} dB");
            }
        }
        last.push(bytes);
    }
    assert!(
        2 * last[1] < last[0],
        "the last 10 P-frames: {} bytes plain, {} held",
        last[0],
        last[1]
    );
}

#[test]
fn a_target_that_pays_for_it_encodes_a_still_picture_finer() {
    // At 0.1 bits per pixel of a 60 fps frame the quality range narrows to QP 10
    // (`rate_guard::FINE_BITS_PER_PIXEL`): 460.8 kbit/s at 320×240.
    let (w, h) = (320, 240);
    let rgba = still("bunny-marble", w, h);
    let mut runs = Vec::new();
    for kbps in [460, 461] {
        let mut stream = H264Stream::new(H264Config {
            kbps,
            keyframe_every: Duration::from_secs(3600),
        });
        let mut decoder = Decoder::new().unwrap();
        let (mut key, mut db) = (0, Vec::new());
        for k in 0..12u64 {
            let f = stream.encode_at(&rgba, w, h, k * 16).unwrap();
            if k == 0 {
                key = f.bytes.len();
            }
            db.push(psnr(&rgba, &decode(&mut decoder, &f.bytes)));
        }
        eprintln!("{kbps} kbit/s: keyframe {key} bytes, {db:.2?} dB");
        runs.push((key, db));
    }
    let (coarse, fine) = (&runs[0], &runs[1]);
    assert!(
        fine.0 > coarse.0,
        "keyframes {} and {} bytes",
        coarse.0,
        fine.0
    );
    for (k, (c, f)) in coarse.1.iter().zip(&fine.1).enumerate() {
        assert!(f > c, "frame {k}: {c:.2} dB coarse, {f:.2} fine");
    }
}
