//! The knob panel: a box the page shows reaches the server as a knob it accepts.

use crate::harness::{
    assert_no_server_errors, change, eval, gaze_at, screenshot, wait_for, Fixture, COLOURS,
};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_coarse_gather_box_is_sent_and_accepted_on_the_full_preset() {
    let f = Fixture::start(&[]).await;
    let page = f.page().await;
    gaze_at(&page, 0.5, 0.5).await;
    let frame = "window.fovea.lastHeader.frame";
    let before = eval(&page, frame).await.as_u64().unwrap();
    eval(&page, &change("preset", "e.value = 'full'")).await;
    wait_for(
        &page,
        &format!("window.fovea.lastHeader.frame > {before}"),
        60,
    )
    .await;
    // The box goes out as a settings knob: the server renders a settings frame for it and
    // answers with no error (a knob it did not know would be refused by name).
    let before = eval(&page, frame).await.as_u64().unwrap();
    eval(&page, &change("coarse_gather", "e.checked = true")).await;
    let h = wait_for(
        &page,
        &format!("window.fovea.lastHeader.frame > {before} && window.fovea.lastHeader"),
        60,
    )
    .await;
    assert_eq!(h["trigger"], "settings", "{h}");
    assert_no_server_errors(&page).await;
    assert!(
        eval(&page, COLOURS).await.as_u64().unwrap() > 50,
        "the canvas shows the scene"
    );
    eval(&page, "document.getElementById('knobs-button').click()").await;
    screenshot(&page, "coarse-gather-knob").await;
    drop(page);
    f.finish();
}
