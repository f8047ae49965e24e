//! Optical flow timings: forward + backward flow with the forward–backward check at 1024×436
//! (the paper's Sintel size) for each preset, native release, one thread, on the synthetic
//! street scene. Run with `cargo bench --bench flow`; `cargo bench --bench flow -- medium` times
//! only the named presets.

mod common;

use superpixel_soup::flow::{FlowParams, Preset, compute_flow};
use superpixel_soup::synth::{SceneKind, render};

fn main() {
    let Ok(scene) = render(SceneKind::Street, 1024, 436) else {
        eprintln!("cannot render the street scene");
        return;
    };
    common::print_header(
        "Optical flow (DIS + variational refinement), forward + backward, single thread, native release",
    );
    let wanted: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    for preset in Preset::ALL {
        if !wanted.is_empty() && !wanted.iter().any(|w| w == preset.name()) {
            continue;
        }
        let params = FlowParams::preset(preset);
        let times = common::time_ms(5, || {
            compute_flow(&scene.frame1, &scene.frame2, &params, &mut |_| {})
        });
        common::print_row(
            &format!("flow, preset {}", preset.name()),
            "1024×436",
            &times,
        );
    }
}
