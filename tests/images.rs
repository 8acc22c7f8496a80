//! The image assertion itself: equal images pass, a difference within the bound passes, and a
//! failure leaves actual, expected and FLIP images where its message says.

mod common;

use common::images::{assert_image, failure_dir, Bound, IDENTICAL};

fn grey(w: u32, h: u32, v: u8) -> Vec<u8> {
    (0..w * h).flat_map(|_| [v, v, v, 255]).collect()
}

#[test]
fn equal_images_and_small_differences_within_the_bound_pass() {
    let a = grey(16, 8, 100);
    assert_image("equal", &a, &a, 16, 8, IDENTICAL);
    let mut b = a.clone();
    b[0] = 101;
    let loose = Bound {
        max_flip: 0.05,
        device: "this test: one level of one channel",
    };
    assert_image("within", &b, &a, 16, 8, loose);
}

#[test]
fn a_failure_writes_the_three_images_and_names_the_folder() {
    let (a, b) = (grey(16, 8, 40), grey(16, 8, 200));
    let dir = failure_dir("deliberate_failure");
    let _ = std::fs::remove_dir_all(&dir);
    let panic = std::panic::catch_unwind(|| {
        assert_image("deliberate_failure", &b, &a, 16, 8, IDENTICAL);
    })
    .expect_err("different images must fail");
    let message = panic.downcast_ref::<String>().cloned().unwrap_or_default();
    assert!(message.contains(&dir.display().to_string()), "{message}");
    assert!(
        message.contains("any adapter"),
        "the bound names its device: {message}"
    );
    for name in ["actual.png", "expected.png", "flip.png"] {
        let img = image::open(dir.join(name)).expect(name);
        assert_eq!((img.width(), img.height()), (16, 8), "{name}");
    }
}
