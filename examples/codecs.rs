//! Codec comparison along a recorded gaze path: bytes, encode time and quality of JPEG and
//! H.264, each with and without foveated encoding (the low-pass; for JPEG also the 20° inset),
//! on the same rendered frames. Inter-frame
//! coding is measured on moving gaze, not on a still frame.
//!
//! `cargo run --release --example codecs -- [OUT] [WxH] [FRAMES] [SCENE]`
//! (defaults /tmp/codecs, 1280x720, 24, gallery). Frames follow the 1000 Hz shipped recording
//! from 20 s on, one every 1/30 s. Quality is FLIP against the lossless frame, within 5° of the
//! gaze (foveal) and over the whole frame, on every third frame; bytes and times on all.

use std::time::Instant;

use fovea::encode::foveated::{low_pass, LowPass};
use fovea::encode::h264::{H264Config, H264Stream};
use fovea::encode::{encode, inset};
use fovea::gaze::formats::{parse, ParseOptions};
use fovea::protocol::Codec;
use fovea::quality::{flip_map, pixels_per_degree};
use fovea::render::{FrameRequest, Renderer};
use fovea::viewing::{Display, Viewing};
use openh264::decoder::Decoder;

struct Config {
    name: String,
    h264_kbps: Option<u32>,
    jpeg_q: u8,
    foveated: bool,
    /// Inset encoding (JPEG): the inset's width, degrees.
    inset_deg: Option<f64>,
}

#[derive(Default)]
struct Tally {
    bytes: Vec<usize>,
    encode_ms: Vec<f64>,
    foveal: Vec<f64>,
    whole: Vec<f64>,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let out = std::path::PathBuf::from(args.first().cloned().unwrap_or("/tmp/codecs".into()));
    let (w, h) = args
        .get(1)
        .and_then(|s| s.split_once('x'))
        .and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)))
        .unwrap_or((1280u32, 720u32));
    let frames: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(24);
    let scene = args
        .get(3)
        .cloned()
        .unwrap_or(fovea::scene::DEFAULT_SCENE.into());
    std::fs::create_dir_all(&out)?;
    let text = std::fs::read_to_string("assets/gaze/eyelink_1000hz_1920x1080.csv")?;
    let rec = parse(
        &text,
        &ParseOptions {
            screen: Some((1920, 1080)),
            ..Default::default()
        },
    )?;
    let gaze_at = |t: f64| -> [f64; 2] {
        let i = rec.samples.partition_point(|s| s.t_ms < t);
        rec.samples[i..]
            .iter()
            .find_map(fovea::gaze::sendable)
            .unwrap_or([0.5, 0.5])
    };
    let viewing = Viewing::new(Display::default(), w, h);
    let ppd = pixels_per_degree(&viewing);
    let mut renderer = Renderer::new()?;
    eprintln!(
        "rendering {frames} frames of {scene} at {w}x{h} on {}",
        renderer.adapter()
    );
    let mut rendered = Vec::new();
    for k in 0..frames {
        let g = gaze_at(20_000.0 + k as f64 * 1000.0 / 30.0);
        let mut req = FrameRequest::new(&scene, w, h);
        req.gaze = [g[0] as f32, g[1] as f32];
        rendered.push((g, renderer.render(&req)?.rgba));
    }
    // Mean FLIP within 5° of the gaze and over the whole frame.
    let foveal_and_whole = |reference: &[u8], shown: &[u8], g: [f64; 2]| -> (f64, f64) {
        let map = flip_map(reference, shown, w, h, ppd);
        let gp = viewing.to_pixels(g);
        let fov: Vec<f64> = map
            .iter()
            .enumerate()
            .filter(|(i, _)| {
                let at = [(*i as u32 % w) as f64, (*i as u32 / w) as f64];
                viewing.eccentricity_deg(gp, at) <= 5.0
            })
            .map(|(_, e)| *e)
            .collect();
        (mean(&fov), mean(&map))
    };
    let mut configs = Vec::new();
    for foveated in [false, true] {
        let tag = if foveated { " + foveated" } else { "" };
        for q in [50u8, 75, 85, 95] {
            configs.push(Config {
                name: format!("JPEG q{q}{tag}"),
                h264_kbps: None,
                jpeg_q: q,
                foveated,
                inset_deg: None,
            });
        }
        for kbps in [1000u32, 2000, 4000, 8000] {
            configs.push(Config {
                name: format!("H.264 {kbps} kbit/s{tag}"),
                h264_kbps: Some(kbps),
                jpeg_q: 0,
                foveated,
                inset_deg: None,
            });
        }
    }
    for q in [75u8, 85, 95] {
        configs.push(Config {
            name: format!("JPEG q{q} + inset 20°"),
            h264_kbps: None,
            jpeg_q: q,
            foveated: false,
            inset_deg: Some(20.0),
        });
    }
    let p = LowPass::default();
    let mut table = String::from("| configuration | bytes/frame (median) | kbit/s at 60 fps | foveal FLIP (mean, ≤ 5°) | whole-frame FLIP (mean) | encode ms (median, incl. low-pass and colour conversion) |\n|---|---:|---:|---:|---:|---:|\n");
    for c in &configs {
        let mut t = Tally::default();
        let mut stream = c.h264_kbps.map(|kbps| {
            H264Stream::new(H264Config {
                kbps,
                keyframe_every: std::time::Duration::from_secs(3600),
            })
        });
        let mut decoder = Decoder::new()?;
        for (k, (g, rgba)) in rendered.iter().enumerate() {
            let start = Instant::now();
            let input = if c.foveated {
                low_pass(rgba, w, h, *g, &viewing, &p)
            } else {
                rgba.clone()
            };
            let (bytes, decoded) = match stream.as_mut() {
                Some(s) => {
                    // Timed as frames at 60 fps: the kbit/s column's assumption.
                    let f = s.encode_at(&input, w, h, (k as f64 * 1000.0 / 60.0) as u64)?;
                    let ms = start.elapsed().as_secs_f64() * 1e3;
                    t.encode_ms.push(ms);
                    let yuv = decoder
                        .decode(&f.bytes)?
                        .ok_or_else(|| anyhow::anyhow!("no picture"))?;
                    // Rounded, as a browser's decoder shows it (openh264's own truncates).
                    (f.bytes, fovea::encode::yuv::picture_to_rgba(&yuv))
                }
                None => match c.inset_deg {
                    Some(deg) => {
                        let plan = inset::plan(w, h, *g, &viewing, deg, &p);
                        let (base, crop) = inset::split(&input, w, h, &plan);
                        let (bw, bh) = plan.base_size(w, h);
                        let jpeg = |px: &[u8], pw, ph| encode(px, pw, ph, Codec::Jpeg, c.jpeg_q);
                        let (b, i) = (jpeg(&base, bw, bh)?, jpeg(&crop, plan.width, plan.height)?);
                        t.encode_ms.push(start.elapsed().as_secs_f64() * 1e3);
                        let back =
                            |b: &[u8]| image::load_from_memory(b).map(|d| d.to_rgba8().into_raw());
                        let shown = inset::compose(&back(&b)?, &back(&i)?, &plan, w, h);
                        ([b, i].concat(), shown)
                    }
                    None => {
                        let b = encode(&input, w, h, Codec::Jpeg, c.jpeg_q)?;
                        t.encode_ms.push(start.elapsed().as_secs_f64() * 1e3);
                        let back = image::load_from_memory(&b)?.to_rgba8().into_raw();
                        (b, back)
                    }
                },
            };
            t.bytes.push(bytes.len());
            if k % 3 == 2 {
                let (f, a) = foveal_and_whole(rgba, &decoded, *g);
                t.foveal.push(f);
                t.whole.push(a);
                if k + 1 == frames - frames % 3 || k + 3 >= frames {
                    let name = c.name.replace([' ', '/', '+', '.'], "_");
                    image::save_buffer(
                        out.join(format!("{name}.png")),
                        &decoded,
                        w,
                        h,
                        image::ColorType::Rgba8,
                    )?;
                }
            }
        }
        let bytes = median(t.bytes.iter().map(|&b| b as f64).collect());
        let kbps =
            mean(&t.bytes.iter().map(|&b| b as f64).collect::<Vec<_>>()) * 8.0 * 60.0 / 1000.0;
        let row = format!(
            "| {} | {:.0} | {:.0} | {:.4} | {:.4} | {:.1} |\n",
            c.name,
            bytes,
            kbps,
            mean(&t.foveal),
            mean(&t.whole),
            median(t.encode_ms.clone())
        );
        eprint!("{row}");
        table.push_str(&row);
    }
    // The floor under every codec that codes 8-bit 4:2:0 YCbCr: the colour conversion alone,
    // rounded (ours) and truncated (openh264's), no compression.
    for (name, ours) in [
        ("I420 round trip, rounded (no codec)", true),
        (
            "I420 round trip, openh264's truncating conversion (no codec)",
            false,
        ),
    ] {
        let (mut fov, mut whole) = (Vec::new(), Vec::new());
        for (g, rgba) in rendered.iter().skip(2).step_by(3) {
            let back = if ours {
                let mut pic = fovea::encode::yuv::I420::new(w as usize, h as usize);
                pic.fill(rgba);
                fovea::encode::yuv::picture_to_rgba(&pic)
            } else {
                let pic = openh264::formats::YUVBuffer::from_rgba8_source(
                    openh264::formats::RgbaSliceU8::new(rgba, (w as usize, h as usize)),
                );
                fovea::encode::yuv::picture_to_rgba(&pic)
            };
            let (f, a) = foveal_and_whole(rgba, &back, *g);
            fov.push(f);
            whole.push(a);
        }
        let row = format!(
            "| {name} | – | – | {:.4} | {:.4} | – |\n",
            mean(&fov),
            mean(&whole)
        );
        eprint!("{row}");
        table.push_str(&row);
    }
    std::fs::write(out.join("codecs.md"), &table)?;
    println!("{table}");
    Ok(())
}
