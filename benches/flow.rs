//! Optical flow timings: forward + backward flow with the forward–backward check at 1024×436
//! (the paper's Sintel size) for each preset, native release, one thread, on the synthetic
//! street scene. Run with `cargo bench --bench flow`; `cargo bench --bench flow -- medium` times
//! only the named presets, `-- edges` only the last row: the motion-edge sharpening alone at
//! full resolution, both directions (part of the fine and high rows; medium sharpens at half
//! resolution, fast at a quarter). A second table gives each preset's peak heap memory (bytes
//! the flow allocates at once at its peak, its result included, counted by the bench's
//! allocator), in bytes per pixel: what the page's worker needs on top of the frames when it
//! computes the flow.

mod common;

/// Counts the flow's heap (native only: the wasm build has an allocator of its own, which
/// reports failed allocations to the page).
#[cfg(not(target_arch = "wasm32"))]
#[global_allocator]
static HEAP: common::PeakHeap = common::PeakHeap::new();

use superpixel_soup::flow::edges::sharpen_motion_edges;
use superpixel_soup::flow::{EdgeParams, FlowParams, Preset, compute_flow};
use superpixel_soup::image::Frame;
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
        if !is_wanted(&wanted, preset.name()) {
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
    if is_wanted(&wanted, "edges") {
        time_edges(&scene.frame1, &scene.frame2);
    }
    #[cfg(not(target_arch = "wasm32"))]
    print_peak_memory(&scene.frame1, &scene.frame2, &wanted);
}

/// Whether the bench's arguments ask for the row `name` (a preset's name or `edges`): every row
/// when none are given.
fn is_wanted(wanted: &[String], name: &str) -> bool {
    wanted.is_empty() || wanted.iter().any(|w| w == name)
}

/// The row of the motion-edge sharpening alone, both directions, at full resolution.
fn time_edges(frame1: &Frame, frame2: &Frame) {
    let unsharpened = FlowParams {
        edges: EdgeParams {
            band: 0,
            ..EdgeParams::default()
        },
        ..FlowParams::preset(Preset::High)
    };
    let Ok(pair) = compute_flow(frame1, frame2, &unsharpened, &mut |_| {}) else {
        eprintln!("cannot compute the street's flow");
        return;
    };
    let edges = EdgeParams::default();
    let times = common::time_ms(5, || {
        sharpen_motion_edges(&pair.forward, frame1, &edges)?;
        sharpen_motion_edges(&pair.backward, frame2, &edges)
    });
    common::print_row(
        "motion-edge sharpening at full resolution, both directions (in the fine and high rows)",
        "1024×436",
        &times,
    );
}

/// The table of each wanted preset's peak heap memory during one flow computation.
#[cfg(not(target_arch = "wasm32"))]
fn print_peak_memory(frame1: &Frame, frame2: &Frame, wanted: &[String]) {
    let presets: Vec<Preset> = Preset::ALL
        .into_iter()
        .filter(|p| is_wanted(wanted, p.name()))
        .collect();
    if presets.is_empty() {
        return;
    }
    println!(
        "\nPeak heap memory of the flow (one run; its result counted, the frames themselves not)\n"
    );
    println!("| what | size | peak MiB | bytes per pixel |");
    println!("| --- | --- | --- | --- |");
    let (width, height) = frame1.size();
    let pixels = (width * height) as f64;
    for preset in presets {
        let params = FlowParams::preset(preset);
        let bytes = HEAP.peak_during(|| compute_flow(frame1, frame2, &params, &mut |_| {})) as f64;
        println!(
            "| flow, preset {} | 1024×436 | {:.1} | {:.0} |",
            preset.name(),
            bytes / f64::from(1u32 << 20),
            bytes / pixels
        );
    }
}
