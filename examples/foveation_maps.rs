//! Pictures of the foveated path for docs/images: the sampling probability, the shaded samples,
//! the reconstruction and its error against the full render of the same frame.
//!
//! `cargo run --release --example foveation_maps -- [SCENE] [WxH] [PRESET] [OUT_DIR] [RECONSTRUCTION] [FOVEATION_PATCH_JSON]`

use anyhow::{Context, Result};
use fovea::foveation::pull_push;
use fovea::render::uniforms::{FLAG_COVERED, FLAG_REUSED, FLAG_SAMPLED};
use fovea::render::{FrameRequest, Renderer};
use fovea::render::{Inspection, PullPushInputs};
use fovea::scene::Scene;
use fovea::settings::{Preset, Reconstruction, RenderSettings};

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene = args.first().map_or("gallery", String::as_str);
    let size = args.get(1).map_or("640x480", String::as_str);
    let preset = args.get(2).map_or("balanced", String::as_str);
    let out = std::path::PathBuf::from(args.get(3).map_or("docs/images", String::as_str));
    let (w, h) = size
        .split_once('x')
        .and_then(|(a, b)| Some((a.parse::<u32>().ok()?, b.parse::<u32>().ok()?)))
        .context("size is WxH")?;
    let mut r = Renderer::new()?;
    let mut full = FrameRequest::new(scene, w, h);
    full.marker = false;
    full.settings = RenderSettings::of(Preset::Full);
    full.stream = 1;
    let reference = r.render(&full)?;
    let mut fov = full.clone();
    fov.stream = 2;
    fov.settings = RenderSettings::of(
        Preset::from_name(preset).with_context(|| format!("no preset {preset}"))?,
    );
    // Extra knobs as a JSON patch of the foveation settings, e.g. {"edges_at_mar":true}.
    if let Some(rec) = args.get(4) {
        fov.settings.foveation.reconstruction =
            serde_json::from_value(serde_json::Value::String(rec.clone()))?;
    }
    if let Some(patch) = args.get(5) {
        let mut v = serde_json::to_value(fov.settings.foveation)?;
        if let (Some(o), serde_json::Value::Object(p)) =
            (v.as_object_mut(), serde_json::from_str(patch)?)
        {
            o.extend(p);
        }
        fov.settings.foveation = serde_json::from_value(v)?;
    }
    let mut label = args
        .get(4)
        .map_or(preset.to_string(), |r| format!("{preset}-{r}"));
    if args.len() > 5 {
        label.push_str("-patched");
    }
    let frame = r.render(&fov)?;
    let ins = r.inspect(2, scene, w, h)?;
    let n = (w * h) as usize;
    let mut prob = vec![0u8; n * 3];
    let mut samples = vec![0u8; n * 3];
    let mut err = vec![0u8; n * 3];
    for k in 0..n {
        let p = ins.probability[k];
        let g = (p.sqrt() * 255.0) as u8;
        prob[3 * k..3 * k + 3].copy_from_slice(&[g, g, g]);
        let f = ins.flags[k];
        let c = if f & FLAG_SAMPLED != 0 {
            [255, 255, 255]
        } else if f & FLAG_REUSED != 0 {
            [60, 90, 200]
        } else if f & FLAG_COVERED != 0 {
            [40, 40, 40]
        } else {
            [0, 0, 0]
        };
        samples[3 * k..3 * k + 3].copy_from_slice(&c);
        let d = (0..3)
            .map(|c| {
                (i32::from(frame.rgba[4 * k + c]) - i32::from(reference.rgba[4 * k + c])).abs()
            })
            .max()
            .unwrap_or(0);
        let e = (d * 8).min(255) as u8;
        err[3 * k..3 * k + 3].copy_from_slice(&[e, e, e]);
    }
    let save = |name: &str, px: &[u8]| -> Result<()> {
        let path = out.join(format!("foveation-{scene}-{label}-{name}.png"));
        image::save_buffer(&path, px, w, h, image::ColorType::Rgb8)?;
        println!("wrote {}", path.display());
        Ok(())
    };
    std::fs::create_dir_all(&out)?;
    save("probability", &prob)?;
    save("samples", &samples)?;
    save("error", &err)?;
    if fov.settings.foveation.reconstruction == Reconstruction::PullPush {
        levels(&fov, &ins, &save)?;
    }
    let rgb: Vec<u8> = frame
        .rgba
        .chunks(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    save("frame", &rgb)?;
    println!(
        "shaded {:.1}% passes {:?}",
        frame.sampled * 100.0,
        frame.passes_ms
    );
    Ok(())
}

/// The pull-push pyramid of this frame (CPU twin, from the frame's own samples): levels 1, 3
/// and 5 drawn at pixel size (each cell's plane at its centre times the pixel's proxy), coarse
/// to fine, to show what each level fills in.
fn levels(
    req: &FrameRequest,
    ins: &Inspection,
    save: &dyn Fn(&str, &[u8]) -> Result<()>,
) -> Result<()> {
    let (w, h) = (req.width, req.height);
    let scene = Scene::builtin(&req.scene)?;
    let n = (w * h) as usize;
    let PullPushInputs {
        proxy,
        samples,
        keys,
    } = ins.pull_push_inputs(&scene, req.light_direction(&scene));
    let pyramid = pull_push::pyramid(w, h, &samples, &keys);
    for level in [1u32, 3, 5] {
        let Some(cells) = pyramid.get(level as usize) else {
            continue;
        };
        let (lw, _) = pull_push::level_size(w, h, level);
        let mut px = vec![0u8; n * 3];
        for k in 0..n {
            if ins.flags[k] & FLAG_COVERED == 0 {
                continue;
            }
            let (x, y) = ((k as u32 % w) >> level, (k as u32 / w) >> level);
            let c = cells[(y * lw + x) as usize].c;
            for ch in 0..3 {
                let linear = (c[ch] * proxy[k][ch]).clamp(0.0, 1.0);
                px[3 * k + ch] = (linear.powf(1.0 / 2.2) * 255.0) as u8;
            }
        }
        save(&format!("level{level}"), &px)?;
    }
    Ok(())
}
