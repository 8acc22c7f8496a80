//! Foveated encoding in the page: an inset frame (a downscaled whole frame plus a
//! full-resolution square on the gaze) is composed on the canvas where the gaze was.

use serde_json::Value;

use crate::harness::{eval, gaze_at, screenshot, wait_for, Fixture, COLOURS};

/// The mean absolute difference between the canvas and the inset image drawn alone, over the
/// inset's unfeathered core (0 when the page put the inset where the header says).
const CORE_DIFFERENCE: &str = r#"(async () => {
  const h = window.fovea.lastHeader;
  const i = h.inset;
  const canvas = document.getElementById('view');
  const shown = canvas.getContext('2d').getImageData(0, 0, canvas.width, canvas.height).data;
  const bytes = new Uint8Array(window.fovea.lastImage);
  const inset = await createImageBitmap(new Blob([bytes.subarray(bytes.length - i.inset_bytes)], { type: 'image/jpeg' }));
  const c = new OffscreenCanvas(i.width, i.height);
  const ctx = c.getContext('2d');
  ctx.drawImage(inset, 0, 0);
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

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_inset_frame_is_composed_where_the_gaze_was() {
    let f = Fixture::start(&[]).await;
    let page = f.page().await;
    eval(&page, "(() => { const s = document.getElementById('encoding'); s.value = 'inset'; s.dispatchEvent(new Event('change')); return true; })()").await;
    wait_for(
        &page,
        "window.fovea.lastHeader && window.fovea.lastHeader.inset != null",
        30,
    )
    .await;
    for (x, y) in [(0.35, 0.45), (0.6, 0.55)] {
        let shown = eval(&page, "window.fovea.framesShown")
            .await
            .as_u64()
            .unwrap();
        gaze_at(&page, x, y).await;
        wait_for(&page, &format!("window.fovea.framesShown > {shown}"), 20).await;
    }
    let h = eval(&page, "window.fovea.lastHeader").await;
    let i = &h["inset"];
    let (w, ht) = (h["width"].as_f64().unwrap(), h["height"].as_f64().unwrap());
    let centre = [
        i["x"].as_f64().unwrap() + i["width"].as_f64().unwrap() / 2.0,
        i["y"].as_f64().unwrap() + i["height"].as_f64().unwrap() / 2.0,
    ];
    let gaze = [
        h["gaze"]["x"].as_f64().unwrap() * w,
        h["gaze"]["y"].as_f64().unwrap() * ht,
    ];
    assert!(
        (centre[0] - gaze[0]).abs() <= 2.0 && (centre[1] - gaze[1]).abs() <= 2.0,
        "inset centred on the gaze: {centre:?} vs {gaze:?}"
    );
    assert!(
        i["base_width"].as_f64().unwrap() < w,
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
    assert!(eval(&page, "window.fovea.errors.length").await == Value::from(0));
    screenshot(&page, "inset").await;
    drop(page);
    f.finish();
}
