//! Foveation only where it wins, end to end: where the render thread's cost model says a
//! foveated frame of a scene costs no less than the frame shaded whole, a foveated session's
//! frames are shaded whole, the same image as asking for them whole, and the header says why;
//! on a scene where foveation pays, nothing changes. The costs are told to the model (a fast
//! GPU's balance between fixed passes and shading is what this guards against, and this
//! machine has none), the frames are real.

mod common;

use std::time::Duration;

use fovea::client::{Client, Event};
use fovea::protocol::{FrameHeader, Hello};
use fovea::render::cost::CostModel;
use fovea::render::{FrameRequest, RenderThread, Renderer};
use fovea::server::ServerOptions;
use fovea::settings::{Preset, RenderSettings};

const WAIT: Duration = Duration::from_secs(120);
const SIZE: (u32, u32) = (96, 64);

fn balanced(scene: &str, stream: u64) -> FrameRequest {
    FrameRequest {
        settings: RenderSettings::of(Preset::Balanced),
        stream,
        ..FrameRequest::new(scene, SIZE.0, SIZE.1)
    }
}

fn whole(mut r: FrameRequest) -> FrameRequest {
    r.settings.foveation.enabled = false;
    r
}

/// A model that has seen `gallery` cost more foveated than whole, and `bunny-marble` the
/// other way round.
fn told_costs() -> CostModel {
    let cost = CostModel::default();
    cost.record(&balanced("gallery", 1), 60.0);
    cost.record(&whole(balanced("gallery", 1)), 40.0);
    cost.record(&balanced("bunny-marble", 1), 20.0);
    cost.record(&whole(balanced("bunny-marble", 1)), 100.0);
    cost
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_render_thread_shades_whole_what_foveation_cannot_win() {
    let renderer = Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"));
    let (render, thread) = RenderThread::spawn_with(renderer, told_costs()).unwrap();
    let f = render.render(balanced("gallery", 1)).await.unwrap().frame;
    assert_eq!(f.sampled, 1.0);
    let why = f.unfoveated.clone().unwrap_or_default();
    assert_eq!(
        why,
        "shaded whole: foveation does not pay here (foveated ~60 ms, shaded whole ~40 ms)"
    );
    let asked_whole = render
        .render(whole(balanced("gallery", 2)))
        .await
        .unwrap()
        .frame;
    assert_eq!(asked_whole.unfoveated, None);
    assert!(
        f.rgba == asked_whole.rgba,
        "the same image as asking for it whole"
    );

    let g = render
        .render(balanced("bunny-marble", 3))
        .await
        .unwrap()
        .frame;
    assert!(g.sampled < 0.5, "foveated where it pays: {}", g.sampled);
    assert_eq!(g.unfoveated, None);
    drop(render);
    thread.join().unwrap();
}

async fn first_frame(url: &str, scene: &str) -> FrameHeader {
    let mut c = Client::connect(url).await.unwrap();
    c.hello(&Hello {
        width: SIZE.0,
        height: SIZE.1,
        preset: "balanced".into(),
        scene: scene.into(),
        ..Default::default()
    })
    .await
    .unwrap();
    loop {
        match c.next_event(WAIT).await.unwrap() {
            Event::Frame { header, .. } => return header,
            Event::Error(e) => panic!("{scene}: {e:?}"),
            _ => {}
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_session_is_told_when_its_frames_are_shaded_whole() {
    let renderer = Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"));
    let addr = "127.0.0.1:0".parse().unwrap();
    let (addr, server) =
        common::start_with(addr, ServerOptions::default(), renderer, told_costs()).await;
    let url = format!("ws://{addr}/ws");
    let h = first_frame(&url, "gallery").await;
    assert_eq!(h.sampled, 1.0);
    assert!(
        h.unfoveated
            .as_deref()
            .is_some_and(|w| w.contains("does not pay")),
        "{h:?}"
    );
    let h = first_frame(&url, "bunny-marble").await;
    assert!(h.sampled < 0.5 && h.unfoveated.is_none(), "{h:?}");
    server.stop().await;
}

#[test]
fn explain_says_whether_foveation_pays_and_measures_it_when_asked() {
    let run = |args: &[&str]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_fovea"))
            .args(args)
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout).into_owned();
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        (out.status.success(), text, err)
    };
    let line = |text: &str| {
        text.lines()
            .find(|l| l.trim_start().starts_with("foveation:"))
            .unwrap_or_else(|| panic!("no foveation line: {text}"))
            .to_string()
    };
    let base = [
        "render",
        "--scene",
        "gallery",
        "--size",
        "96x64",
        "--explain",
    ];
    let (ok, text, err) = run(&base);
    assert!(ok, "{err}");
    assert!(line(&text).contains("foveation: on, unless"), "{text}");
    let (ok, text, err) = run(&[&base[..], &["--preset", "full"]].concat());
    assert!(ok, "{err}");
    assert!(line(&text).contains("foveation: off"), "{text}");
    let (ok, text, err) = run(&[&base[..], &["--measure"]].concat());
    assert!(ok, "{err}");
    let l = line(&text);
    assert!(
        (l.contains("foveation: pays") || l.contains("foveation: does not pay"))
            && l.contains("at 96x64")
            && l.contains("foveated ~")
            && l.contains("shaded whole ~"),
        "{l}"
    );
    let (ok, _, err) = run(&[
        "render",
        "--scene",
        "gallery",
        "--measure",
        "--out",
        "x.png",
    ]);
    assert!(
        !ok && err.contains("--explain"),
        "--measure needs --explain: {err}"
    );
}
