#![cfg(not(target_arch = "wasm32"))]
//! The web page's built-in sample (www/sample/) is exactly what the project's own generator
//! renders: `soup synth --scene street --size 768x328`, the case files frame1.png, frame2.png and
//! intrinsics.txt. After a deliberate change to the synthetic scenes, regenerate the sample with
//! scripts/make-sample.sh.

use std::path::Path;

use superpixel_soup::formats::case::{Case, write_case};
use superpixel_soup::synth::{SceneKind, render};

#[test]
fn the_committed_sample_is_what_the_generator_renders() {
    let scene = render(SceneKind::Street, 768, 328).unwrap();
    let dir = std::env::temp_dir().join(format!("soup-sample-{}", std::process::id()));
    write_case(
        &dir,
        &Case {
            name: "street".into(),
            frame1: scene.frame1,
            frame2: scene.frame2,
            intrinsics: Some(scene.intrinsics),
            depth1: None,
            flow12: None,
            depth12: None,
            moving1: None,
            groups1: None,
        },
    )
    .unwrap();
    let committed = Path::new(env!("CARGO_MANIFEST_DIR")).join("www/sample");
    for name in ["frame1.png", "frame2.png", "intrinsics.txt"] {
        let fresh = std::fs::read(dir.join(name)).unwrap();
        let shipped = std::fs::read(committed.join(name)).unwrap();
        assert!(
            fresh == shipped,
            "www/sample/{name} differs from what `soup synth --scene street --size 768x328` \
             renders now; run scripts/make-sample.sh"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
