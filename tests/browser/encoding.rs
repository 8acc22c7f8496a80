//! Codecs and foveated encoding in the page: the default codec is H.264 where WebCodecs
//! decodes it and JPEG where not; an inset frame (a downscaled whole frame plus a
//! full-resolution square on the gaze) is composed on the canvas where the gaze was, and a
//! low-passed, held H.264 stream decodes.

use serde_json::Value;

use crate::harness::{
    assert_no_server_errors, change, choose, choose_h264, eval, gaze_and_frame, mouse_at,
    screenshot, slowed, wait_for, Fixture, COLOURS,
};

/// The mean absolute difference between the canvas and the inset image drawn alone, over the
/// inset's unfeathered core (0 when the page put the inset where the header says). The inset
/// is the second JPEG of the frame's bytes, or over H.264 the picture's inset part
/// (`inset.packed.inset_x` onwards: not its base or its padding).
const CORE_DIFFERENCE: &str = r#"(async () => {
  const h = window.fovea.lastHeader;
  const i = h.inset;
  const canvas = document.getElementById('view');
  const shown = canvas.getContext('2d').getImageData(0, 0, canvas.width, canvas.height).data;
  const c = new OffscreenCanvas(i.width, i.height);
  const ctx = c.getContext('2d');
  if (i.packed) {
    ctx.drawImage(window.fovea.lastImage, i.packed.inset_x, 0, i.width, i.height, 0, 0, i.width, i.height);
  } else {
    const bytes = new Uint8Array(window.fovea.lastImage);
    const inset = await createImageBitmap(new Blob([bytes.subarray(bytes.length - i.inset_bytes)], { type: 'image/jpeg' }));
    ctx.drawImage(inset, 0, 0);
  }
  const own = ctx.getImageData(0, 0, i.width, i.height).data;
  const m = Math.ceil(i.feather * i.width) + 1;
  let sum = 0, n = 0;
  for (let y = m; y < i.height - m; y++) {
    for (let x = m; x < i.width - m; x++) {
      const a = ((y + i.y) * canvas.width + x + i.x) * 4, b = (y * i.width + x) * 4;
      for (let k = 0; k < 3; k++) { sum += Math.abs(shown[a + k] - own[b + k]); n++; }
    }
  }
  return n ? sum / n : -1;
})()"#;

/// The last frame's inset centre and gaze, in frame pixels.
fn centre_and_gaze(h: &Value) -> ([f64; 2], [f64; 2]) {
    let i = &h["inset"];
    let num = |v: &Value| v.as_f64().unwrap();
    let centre = [
        num(&i["x"]) + num(&i["width"]) / 2.0,
        num(&i["y"]) + num(&i["height"]) / 2.0,
    ];
    let gaze = [
        num(&h["gaze"]["x"]) * num(&h["width"]),
        num(&h["gaze"]["y"]) * num(&h["height"]),
    ];
    (centre, gaze)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_inset_frame_is_composed_where_the_gaze_was() {
    let f = Fixture::start(&[]).await;
    // Two JPEGs a frame (the H.264 inset has a test of its own).
    let page = f.page_with("codec=jpeg").await;
    eval(&page, &change("encoding", "e.value = 'inset'")).await;
    wait_for(
        &page,
        "window.fovea.lastHeader && window.fovea.lastHeader.inset != null",
        30,
    )
    .await;
    for (x, y) in [(0.35, 0.45), (0.6, 0.55)] {
        gaze_and_frame(&page, x, y).await;
    }
    let h = eval(&page, "window.fovea.lastHeader").await;
    let i = &h["inset"];
    let (centre, gaze) = centre_and_gaze(&h);
    assert!(
        (centre[0] - gaze[0]).abs() <= 2.0 && (centre[1] - gaze[1]).abs() <= 2.0,
        "inset centred on the gaze: {centre:?} vs {gaze:?}"
    );
    assert!(
        i["base_width"].as_f64().unwrap() < h["width"].as_f64().unwrap(),
        "the base is downscaled: {i}"
    );
    let diff = eval(&page, CORE_DIFFERENCE).await.as_f64().unwrap();
    assert!(
        (0.0..1.0).contains(&diff),
        "the canvas shows the inset in its core: mean difference {diff}"
    );
    let colours: u64 = serde_json::from_value(eval(&page, COLOURS).await).unwrap();
    assert!(
        colours > 50,
        "the composed frame shows the scene ({colours} colours)"
    );
    assert_no_server_errors(&page).await;
    screenshot(&page, "inset").await;
    drop(page);
    f.finish();
}

/// The mean step between the canvas's last two columns, over the rows the inset leaves alone.
const EDGE_STEP: &str = r#"(() => {
  const i = window.fovea.lastHeader.inset;
  const canvas = document.getElementById('view');
  const w = canvas.width;
  const px = canvas.getContext('2d').getImageData(w - 2, 0, 2, canvas.height).data;
  let sum = 0, n = 0;
  for (let y = 0; y < canvas.height; y++) {
    if (y >= i.y && y < i.y + i.height && i.x + i.width >= w - 2) continue;
    for (let k = 0; k < 3; k++) { sum += Math.abs(px[y * 8 + k] - px[y * 8 + 4 + k]); n++; }
  }
  return n ? sum / n : -1;
})()"#;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_h264_inset_frame_is_one_picture_composed_where_the_gaze_was() {
    let f = Fixture::start(&[]).await;
    let page = f.page().await;
    eval(
        &page,
        "(() => { window.fovea.keepPictures = true; return true; })()",
    )
    .await;
    choose_h264(
        &page,
        Some("inset"),
        "window.fovea.lastHeader.inset != null && window.fovea.lastImage != null",
    )
    .await;
    let mut places = Vec::new();
    for (x, y) in [(0.35, 0.45), (0.6, 0.55)] {
        gaze_and_frame(&page, x, y).await;
        let h = eval(&page, "window.fovea.lastHeader").await;
        let i = &h["inset"];
        let (centre, gaze) = centre_and_gaze(&h);
        // Placed on the 16-pixel grid near the gaze (a video inset stays put until the gaze
        // drifts 1° or a grid step from its centre: 13 px here).
        let (dx, dy) = ((centre[0] - gaze[0]).abs(), (centre[1] - gaze[1]).abs());
        assert!(
            dx.hypot(dy) <= 14.0,
            "inset near the gaze: {centre:?} vs {gaze:?}"
        );
        assert_eq!(i["x"].as_u64().unwrap() % 16, 0, "on the grid: {i}");
        assert_eq!(i["inset_bytes"], Value::from(0), "one picture: {i}");
        let diff = eval(&page, CORE_DIFFERENCE).await.as_f64().unwrap();
        assert!(
            (0.0..1.0).contains(&diff),
            "the canvas shows the picture's inset part in its core: mean difference {diff}"
        );
        places.push((i["x"].clone(), i["packed"].clone()));
    }
    // The base is scaled up from its own pixels only: the canvas's last column continues the
    // one before it (a browser filtering past the base's rectangle into the picture's inset
    // part drew a line of other colours there).
    let edge = eval(&page, EDGE_STEP).await.as_f64().unwrap();
    assert!((0.0..3.0).contains(&edge), "right-edge step {edge}");
    // The inset moved with the gaze; the picture's layout did not (no new stream).
    assert_ne!(places[0].0, places[1].0);
    assert_eq!(places[0].1, places[1].1);
    let colours: u64 = serde_json::from_value(eval(&page, COLOURS).await).unwrap();
    assert!(
        colours > 50,
        "the frame shows the scene ({colours} colours)"
    );
    assert_no_server_errors(&page).await;
    screenshot(&page, "h264-inset").await;
    drop(page);
    f.finish();
}

/// H.264 with foveated encoding (the periphery low-passed, and held where it changed by less
/// than the eye can tell, the server decoding its own stream on a thread of its own): every
/// frame decodes in the page, P-frames follow the gaze, and the canvas shows the scene.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_foveated_h264_stream_decodes_in_the_page() {
    let f = Fixture::start(&[]).await;
    let page = f.page().await;
    choose_h264(
        &page,
        Some("lowpass"),
        "window.fovea.player && window.fovea.player.decoded >= 1",
    )
    .await;
    // Small moves (most blocks held) and a jump (the periphery taken again).
    for (x, y) in [
        (0.4, 0.5),
        (0.41, 0.5),
        (0.42, 0.51),
        (0.7, 0.3),
        (0.71, 0.3),
    ] {
        gaze_and_frame(&page, x, y).await;
    }
    let mix = eval(
        &page,
        "[window.fovea.player.decoded, window.fovea.player.keyframes, window.fovea.player.errors]",
    )
    .await;
    let (decoded, keys) = (mix[0].as_u64().unwrap(), mix[1].as_u64().unwrap());
    assert!(keys >= 1 && decoded > keys + 3, "P-frames decoded: {mix}");
    assert_eq!(mix[2], Value::from(0), "no decoder error: {mix}");
    let colours: u64 = serde_json::from_value(eval(&page, COLOURS).await).unwrap();
    assert!(
        colours > 50,
        "the decoded frame shows the scene ({colours} colours)"
    );
    assert_no_server_errors(&page).await;
    screenshot(&page, "h264-lowpass").await;
    drop(page);
    f.finish();
}

/// The stats panel says why the frames are JPEG, not H.264, below the frame they describe.
const STATS_SAY_WHY: &str = "(() => { const t = document.getElementById('overlay').textContent; return t.includes('\\nJPEG, not H.264: ') && t.includes(' jpeg'); })()";

/// The codec menu's default, `auto`: H.264 where the browser decodes it, JPEG where it has no
/// WebCodecs, with the reason in the stats and no banner; a viewer who chose H.264 there is
/// told in a banner.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_default_codec_is_h264_where_the_browser_decodes_it_and_jpeg_where_not() {
    let f = Fixture::start(&[]).await;
    let page = f.page().await;
    let shown = "[document.getElementById('codec').value, window.fovea.lastHeader.codec, window.fovea.codecNote]";
    assert_eq!(
        eval(&page, shown).await,
        serde_json::json!(["auto", "h264", null])
    );
    let colours: u64 = serde_json::from_value(eval(&page, COLOURS).await).unwrap();
    assert!(
        colours > 50,
        "the frame shows the scene ({colours} colours)"
    );
    page.close().await.expect("page closes");

    // A browser without WebCodecs: removed before the page's own scripts run.
    let page = f
        .page_after("delete window.VideoDecoder; delete window.EncodedVideoChunk;")
        .await;
    let got = eval(&page, shown).await;
    assert_eq!(got[0], "auto");
    assert_eq!(got[1], "jpeg", "no WebCodecs: {got}");
    let note = got[2].as_str().unwrap_or_default().to_string();
    assert!(note.contains("WebCodecs"), "the reason is kept: {got}");
    wait_for(&page, STATS_SAY_WHY, 10).await;
    let banner =
        "[document.getElementById('banner').hidden, document.getElementById('banner').textContent]";
    assert_eq!(
        eval(&page, banner).await[0],
        Value::Bool(true),
        "the page's own choice needs no banner"
    );
    // Chosen by the viewer, the fallback is announced.
    choose(&page, "codec", "h264", 30).await;
    let b = eval(&page, banner).await;
    assert_eq!(b[0], Value::Bool(false), "a banner: {b}");
    assert!(
        b[1].as_str().is_some_and(|t| t.contains("showing JPEG")),
        "{b}"
    );
    assert_eq!(eval(&page, "window.fovea.lastHeader.codec").await, "jpeg");
    assert_no_server_errors(&page).await;
    wait_for(&page, STATS_SAY_WHY, 10).await;
    screenshot(&page, "no-webcodecs").await;
    drop(page);
    f.finish();
}

/// A browser that says it decodes H.264 and then cannot (as a broken hardware decoder does):
/// after three failures in a row without a picture the page gives up on H.264 and shows JPEG,
/// saying why, instead of asking for keyframes for ever.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_decoder_that_keeps_failing_falls_back_to_jpeg() {
    let f = Fixture::start(&[]).await;
    let page = f
        .page_after(
            "window.VideoDecoder = class extends window.VideoDecoder { \
             decode() { throw new Error('a decoder that cannot decode (test)'); } };",
        )
        .await;
    let got = eval(
        &page,
        "[window.fovea.lastHeader.codec, window.fovea.h264Failed, window.fovea.connects]",
    )
    .await;
    assert_eq!(got[0], "jpeg", "{got}");
    let why = got[1].as_str().unwrap_or_default();
    assert!(
        why.contains("3 times in a row") && why.contains("cannot decode (test)"),
        "{got}"
    );
    assert_eq!(got[2], 2, "one H.264 session, then one JPEG session: {got}");
    wait_for(&page, STATS_SAY_WHY, 10).await;
    // It stays on JPEG: a scene change does not try the failed decoder again.
    choose(&page, "scene", "bunny-marble", 30).await;
    let got = eval(
        &page,
        "[window.fovea.connects, window.fovea.lastHeader.codec]",
    )
    .await;
    assert_eq!(got, serde_json::json!([3, "jpeg"]));
    assert_no_server_errors(&page).await;
    drop(page);
    f.finish();
}

/// The page asks WebCodecs whether it decodes H.264 before it says hello; gaze sent while the
/// browser thinks (the socket already open) would reach the server before the hello and be
/// refused with `no_hello`; it is held and sent after the hello. The probe is slowed so that
/// the mouse moves during it.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn gaze_while_the_codec_is_probed_waits_for_the_hello() {
    let f = Fixture::start(&[]).await;
    let page = f
        .page_after(&slowed(
            "VideoDecoder",
            "isConfigSupported",
            1500,
            "probing",
        ))
        .await;
    let connects = eval(&page, "window.fovea.connects").await;
    eval(&page, &change("scene", "e.value = 'opaque'")).await;
    wait_for(
        &page,
        "window.probing > 0 && window.fovea.ws.readyState === WebSocket.OPEN",
        30,
    )
    .await;
    for x in [0.3, 0.5, 0.7] {
        mouse_at(&page, x).await;
    }
    let shown = format!("window.fovea.connects > {connects} && window.fovea.framesShown >= 1");
    wait_for(&page, &shown, 30).await;
    assert_eq!(eval(&page, "window.fovea.lastHeader.codec").await, "h264");
    // The last gaze held back was sent after the hello: a frame answers it.
    let answered = "(() => { const h = window.fovea.lastHeader; \
                    return h.trigger === 'gaze' && Math.abs(h.gaze.x - 0.7) < 0.01; })()";
    wait_for(&page, answered, 30).await;
    assert_no_server_errors(&page).await;
    drop(page);
    f.finish();
}
