//! SLIC and graph timings at 1024×436 with N = 1500 (the paper's Sintel size), plus the count and
//! boundary recall on each synthetic scene. Run with `cargo bench --bench superpixels`.

mod common;

use superpixel_soup::eval::{boundary_recall, eval_case_dir};
use superpixel_soup::formats::case::read_case;
use superpixel_soup::superpixels::graph::{boundary_graph, knn_graph};
use superpixel_soup::superpixels::{SlicParams, slic};
use superpixel_soup::synth::{SceneKind, render};

fn main() {
    let params = SlicParams::default();
    common::print_header("Superpixels, single thread, native release");
    let mut quality = Vec::new();
    for kind in SceneKind::ALL {
        let Ok(scene) = render(kind, 1024, 436) else {
            eprintln!("cannot render {}", kind.name());
            return;
        };
        let frame = &scene.frame1;
        let times = common::time_ms(5, || slic(frame, &params));
        common::print_row(
            &format!("SLIC N=1500 ({})", kind.name()),
            "1024×436",
            &times,
        );
        let Ok(sp) = slic(frame, &params) else { return };
        let times = common::time_ms(5, || boundary_graph(&sp, frame));
        common::print_row(
            &format!("boundary graph ({})", kind.name()),
            "1024×436",
            &times,
        );
        let times = common::time_ms(5, || knn_graph(&sp, 15, 3.0));
        common::print_row(
            &format!("K-NN graph K=15 ({})", kind.name()),
            "1024×436",
            &times,
        );
        let recall = boundary_recall(&sp.labels, &scene.depth1, 0.05, 2)
            .ok()
            .flatten();
        let smallest = sp.smallest_size();
        quality.push((kind.name().to_string(), sp.len(), smallest, recall));
    }
    if let Some(dir) = eval_case_dir("middlebury-motorcycle")
        && let Ok(case) = read_case(&dir)
        && let Ok(sp) = slic(&case.frame1, &params)
    {
        let times = common::time_ms(5, || slic(&case.frame1, &params));
        common::print_row("SLIC N=1500 (middlebury-motorcycle)", "741×500", &times);
        let recall = case
            .depth1
            .as_ref()
            .and_then(|d| boundary_recall(&sp.labels, d, 0.05, 2).ok().flatten());
        let smallest = sp.smallest_size();
        quality.push(("middlebury-motorcycle".into(), sp.len(), smallest, recall));
    }
    println!("\nSLIC N=1500, compactness 10\n");
    println!("| image | superpixels | smallest (px) | boundary recall (2 px) |");
    println!("| --- | --- | --- | --- |");
    for (name, n, smallest, recall) in quality {
        let recall = recall.map_or("–".to_string(), |r| format!("{r:.3}"));
        println!("| {name} | {n} | {smallest} | {recall} |");
    }
}
