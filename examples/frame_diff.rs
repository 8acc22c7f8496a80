//! Compares two folders of PNG frames of the same names (see `scripts/compare_frames.sh`): per
//! image "identical" or its max and mean FLIP; exits 1 when any differs by more than FLIP 0.001.
//!
//! cargo run --release --example frame_diff -- BEFORE_DIR AFTER_DIR [MAP_DIR]
//!
//! With MAP_DIR, each differing image's FLIP map is written there (grey, white = FLIP 1), to
//! see where two renders differ and not only by how much.

use std::path::Path;

use anyhow::{bail, Context, Result};
use fovea::quality::{flip_map, pixels_per_degree};
use fovea::viewing::Viewing;

const TOLERANCE: f64 = 0.001;

fn load(path: &Path) -> Result<(Vec<u8>, u32, u32)> {
    let img = image::open(path)
        .with_context(|| format!("reading {}", path.display()))?
        .to_rgba8();
    let (w, h) = img.dimensions();
    Ok((img.into_raw(), w, h))
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (before, after, maps) = match args.as_slice() {
        [b, a] => (b, a, None),
        [b, a, m] => (b, a, Some(Path::new(m))),
        _ => bail!("usage: frame_diff BEFORE_DIR AFTER_DIR [MAP_DIR]"),
    };
    if let Some(dir) = maps {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let mut names: Vec<_> = std::fs::read_dir(before)?
        .filter_map(|e| e.ok())
        .map(|e| e.file_name())
        .filter(|n| n.to_string_lossy().ends_with(".png"))
        .collect();
    names.sort();
    if names.is_empty() {
        bail!("no PNG files in {before}");
    }
    let (mut worst, mut exact, mut over) = (0.0f64, 0, 0);
    for name in &names {
        let (a, w, h) = load(&Path::new(before).join(name))?;
        let (b, w2, h2) = load(&Path::new(after).join(name))?;
        if (w, h) != (w2, h2) {
            bail!(
                "{}: {w}x{h} before, {w2}x{h2} after",
                name.to_string_lossy()
            );
        }
        if a == b {
            exact += 1;
            println!("{:32} identical", name.to_string_lossy());
            continue;
        }
        let viewing = Viewing {
            width: w,
            height: h,
            width_cm: 53.0,
            distance_cm: 60.0,
        };
        let map = flip_map(&a, &b, w, h, pixels_per_degree(&viewing));
        if let Some(dir) = maps {
            let grey: Vec<u8> = map.iter().map(|e| (e * 255.0).round() as u8).collect();
            let path = dir.join(name);
            image::GrayImage::from_raw(w, h, grey)
                .context("FLIP map size")?
                .save(&path)
                .with_context(|| format!("writing {}", path.display()))?;
        }
        let max = map.iter().copied().fold(0.0, f64::max);
        let mean = map.iter().sum::<f64>() / map.len() as f64;
        let differing = a.chunks(4).zip(b.chunks(4)).filter(|(p, q)| p != q).count();
        worst = worst.max(max);
        if max > TOLERANCE {
            over += 1;
        }
        println!(
            "{:32} differs: {differing} pixels, FLIP max {max:.5}, mean {mean:.6}",
            name.to_string_lossy()
        );
    }
    println!(
        "{} images: {exact} bit-identical, worst FLIP {worst:.5}, {over} over {TOLERANCE}",
        names.len()
    );
    if over > 0 {
        std::process::exit(1);
    }
    Ok(())
}
