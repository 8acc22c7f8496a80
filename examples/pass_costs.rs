//! Per-pass GPU time of a few configurations on one scene, interleaved frame by frame, without
//! the bench's reference renders: a quick, low-noise check of a pass's cost while changing it.
//!
//! `cargo run --release --example pass_costs -- [SCENE] [WxH] [FRAMES] [CONFIG,...] [moving]`
//! (configuration names as `fovea bench --sweep` takes them). `moving` nudges the camera every
//! frame (1 mm sideways), so nothing that holds only for a still camera is reused.

use std::collections::BTreeMap;

use anyhow::{Context, Result};
use fovea::render::{FrameRequest, Renderer};

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene = args.first().map_or("gallery", String::as_str);
    let (w, h) = args
        .get(1)
        .map_or("640x480", String::as_str)
        .split_once('x')
        .and_then(|(a, b)| Some((a.parse::<u32>().ok()?, b.parse::<u32>().ok()?)))
        .context("size is WxH")?;
    let frames: usize = args.get(2).map_or(Ok(12), |s| s.parse())?;
    let configs = fovea::bench::sweep(args.get(3).map_or("full,balanced", String::as_str))
        .map_err(anyhow::Error::msg)?;
    let moving = args.get(4).is_some_and(|a| a == "moving");
    let mut r = Renderer::new()?;
    r.settle_radiosity(scene, std::time::Duration::from_secs(3600), &|| false)?;
    let mut times: Vec<BTreeMap<String, Vec<f64>>> = vec![BTreeMap::new(); configs.len()];
    for f in 0..frames + 2 {
        for (i, c) in configs.iter().enumerate() {
            let mut req = FrameRequest::new(scene, w, h);
            req.settings = c.settings.clone();
            req.stream = i as u64 + 1;
            if moving {
                let mut camera = r.load_scene(scene)?.file.camera;
                camera.eye[0] += 1e-3 * f as f32;
                req.camera = Some(camera);
            }
            let frame = r.render(&req)?;
            if f < 2 {
                continue;
            }
            let t = &mut times[i];
            t.entry("frame".into()).or_default().push(frame.render_ms);
            for (k, v) in frame.passes_ms {
                t.entry(k).or_default().push(v);
            }
        }
    }
    for (c, t) in configs.iter().zip(times) {
        let med = |v: &Vec<f64>| {
            let mut v = v.clone();
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let parts: Vec<String> = t
            .iter()
            .map(|(k, v)| format!("{k} {:.1}", med(v)))
            .collect();
        println!("{:36} {}", c.name, parts.join(", "));
    }
    Ok(())
}
