//! Optical flow timings: forward + backward flow with the forward–backward check at 1024×436
//! (the paper's Sintel size) for each preset, native release, one thread, on the synthetic
//! street scene. Run with `cargo bench --bench flow`; `cargo bench --bench flow -- medium` times
//! only the named presets, `-- edges` only the last row: the motion-edge sharpening alone at
//! full resolution, both directions (part of the high row; medium sharpens at half resolution,
//! fast at a quarter).

mod common;

use superpixel_soup::flow::edges::sharpen_motion_edges;
use superpixel_soup::flow::{EdgeParams, FlowParams, Preset, compute_flow};
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
    if !wanted.is_empty() && !wanted.iter().any(|w| w == "edges") {
        return;
    }
    let unsharpened = FlowParams {
        edges: EdgeParams {
            band: 0,
            ..EdgeParams::default()
        },
        ..FlowParams::preset(Preset::High)
    };
    let Ok(pair) = compute_flow(&scene.frame1, &scene.frame2, &unsharpened, &mut |_| {}) else {
        eprintln!("cannot compute the street's flow");
        return;
    };
    let edges = EdgeParams::default();
    let times = common::time_ms(5, || {
        sharpen_motion_edges(&pair.forward, &scene.frame1, &edges)?;
        sharpen_motion_edges(&pair.backward, &scene.frame2, &edges)
    });
    common::print_row(
        "motion-edge sharpening at full resolution, both directions (in the high row)",
        "1024×436",
        &times,
    );
}
