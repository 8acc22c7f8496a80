//! Median per-stage frame times from the frame headers of a running server: the measurement
//! behind the walking skeleton's report, until `fovea load` exists.
//!
//! cargo run --release --example frame_times -- ws://127.0.0.1:8080/ws 640 480 120

use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use fovea::client::{Client, Event};
use fovea::protocol::{Ack, Gaze, Hello};

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

#[tokio::main]
async fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (url, w, h, n, preset) = match args.as_slice() {
        [url, w, h, n] => (url, w, h, n, "balanced"),
        [url, w, h, n, preset] => (url, w, h, n, preset.as_str()),
        _ => bail!("usage: frame_times WS_URL WIDTH HEIGHT FRAMES [PRESET]"),
    };
    let (width, height, frames): (u32, u32, usize) = (w.parse()?, h.parse()?, n.parse()?);
    let mut c = Client::connect(url).await?;
    let welcome = c
        .hello(&Hello {
            width,
            height,
            max_in_flight: 1,
            preset: preset.into(),
            ..Hello::default()
        })
        .await?;
    let clock = Instant::now();
    let (mut render, mut readback, mut encode, mut queue, mut round_trip, mut sampled) =
        (vec![], vec![], vec![], vec![], vec![], vec![]);
    const WARM_UP: u64 = 10;
    for seq in 1..=frames as u64 + WARM_UP {
        // Sweep the gaze across the frame so every frame differs.
        let t = (seq as f64 * 0.618).fract();
        let t_ms = clock.elapsed().as_secs_f64() * 1e3;
        c.gaze(&Gaze {
            seq,
            t_ms,
            x: t,
            y: 1.0 - t,
            pupil_mm: Some(4.0),
            sample_t_ms: None,
        })
        .await?;
        let header = loop {
            let ev = c
                .next_event(Duration::from_secs(30))
                .await
                .context("waiting for a frame")?;
            let Event::Frame { header, .. } = ev else {
                continue;
            };
            c.ack(&Ack {
                frame: header.frame,
                t_ms: None,
                dropped: false,
            })
            .await?;
            if header.seq == Some(seq) {
                break header;
            }
        };
        // The first frames warm caches and pipelines; leave them out.
        if seq > WARM_UP {
            render.push(header.stages_ms.render);
            readback.push(header.stages_ms.readback);
            encode.push(header.stages_ms.encode);
            queue.push(header.stages_ms.queue);
            sampled.push(header.sampled);
            round_trip.push(clock.elapsed().as_secs_f64() * 1e3 - t_ms);
        }
    }
    println!("adapter: {}", welcome.adapter);
    println!(
        "{width}x{height} {preset}, {} frames, medians: sampled {:.3}, queue {:.2} ms  render {:.2} ms  readback {:.2} ms  encode {:.2} ms  gaze-to-frame-received {:.2} ms",
        render.len(),
        median(&mut sampled),
        median(&mut queue),
        median(&mut render),
        median(&mut readback),
        median(&mut encode),
        median(&mut round_trip)
    );
    Ok(())
}
