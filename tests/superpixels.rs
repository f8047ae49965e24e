//! SLIC and the superpixel graphs on the synthetic scenes (exact depth for boundary recall) and on
//! a real photo pair from the evaluation data when present (`eval::eval_case_dir`). That the
//! segmentation is the same in a fresh process is tested with the CLI (tests/cli.rs).
#![cfg(not(target_arch = "wasm32"))]

use superpixel_soup::eval::{boundary_recall, eval_case_dir};
use superpixel_soup::formats::case::read_case;
use superpixel_soup::grid::Grid;
use superpixel_soup::image::{Frame, to_lab};
use superpixel_soup::superpixels::graph::{boundary_graph, knn_graph};
use superpixel_soup::superpixels::{SlicParams, Superpixels, slic};
use superpixel_soup::synth::{SceneKind, render};

/// Every label is exactly one 4-connected region, labels have no gaps, the count is within ±15 %
/// of the request, no superpixel is tiny, and each segment's pixel list, bounding box, anchor and
/// mean colours describe its pixels of `frame`.
fn check_segmentation(sp: &Superpixels, frame: &Frame, requested: usize) {
    let (w, h) = sp.labels.size();
    let lab = to_lab(frame);
    for (label, seg) in sp.segments.iter().enumerate() {
        assert!(seg.pixels.windows(2).all(|p| p[0] < p[1]), "scan order");
        assert!(
            seg.pixels
                .iter()
                .all(|&p| sp.labels.data()[p as usize] == label as u32)
        );
        let xy = |p: u32| ((p as usize % w) as f64, (p as usize / w) as f64);
        let n = seg.pixels.len() as f64;
        let (mx, my) = seg.pixels.iter().fold((0.0, 0.0), |(sx, sy), &p| {
            let (x, y) = xy(p);
            (sx + x / n, sy + y / n)
        });
        assert!((seg.anchor[0] - mx).abs() < 1e-6 && (seg.anchor[1] - my).abs() < 1e-6);
        let (xs, ys): (Vec<f64>, Vec<f64>) = seg.pixels.iter().map(|&p| xy(p)).unzip();
        let min_max = |v: &[f64]| {
            v.iter()
                .fold((f64::MAX, 0f64), |(a, b), &c| (a.min(c), b.max(c)))
        };
        let ((x0, x1), (y0, y1)) = (min_max(&xs), min_max(&ys));
        assert_eq!(seg.bbox, [x0, y0, x1, y1].map(|v| v as u32));
        for k in 0..3 {
            let rgb = seg
                .pixels
                .iter()
                .map(|&p| frame.data()[p as usize][k] as f64)
                .sum::<f64>()
                / n;
            assert_eq!(seg.mean_rgb[k], rgb.round() as u8);
            let l = seg
                .pixels
                .iter()
                .map(|&p| lab.data()[p as usize][k] as f64)
                .sum::<f64>()
                / n;
            assert!((seg.mean_lab[k] as f64 - l).abs() < 1e-3);
        }
    }
    let n = sp.len();
    assert!(
        (n as f64 - requested as f64).abs() <= 0.15 * requested as f64,
        "{n} superpixels for {requested}"
    );
    assert!(sp.labels.data().iter().all(|&l| (l as usize) < n));
    let mut seen = vec![false; w * h];
    for (label, seg) in sp.segments.iter().enumerate() {
        assert!(
            seg.pixels.len() >= 8,
            "superpixel {label} has {} pixels",
            seg.pixels.len()
        );
        // Flood fill from the first pixel within the label must reach all of its pixels.
        let mut stack = vec![seg.pixels[0] as usize];
        seen[seg.pixels[0] as usize] = true;
        let mut reached = 0;
        while let Some(p) = stack.pop() {
            reached += 1;
            let (x, y) = (p % w, p / w);
            for (nx, ny) in [
                (x.wrapping_sub(1), y),
                (x + 1, y),
                (x, y.wrapping_sub(1)),
                (x, y + 1),
            ] {
                if nx < w && ny < h && !seen[ny * w + nx] && *sp.labels.get(nx, ny) == label as u32
                {
                    seen[ny * w + nx] = true;
                    stack.push(ny * w + nx);
                }
            }
        }
        assert_eq!(
            reached,
            seg.pixels.len(),
            "superpixel {label} is not one connected region"
        );
        let [x0, y0, x1, y1] = seg.bbox;
        assert!(
            seg.anchor[0] >= x0 as f64
                && seg.anchor[0] <= x1 as f64
                && seg.anchor[1] >= y0 as f64
                && seg.anchor[1] <= y1 as f64
        );
    }
}

#[test]
fn synthetic_scenes_segment_cleanly_with_high_boundary_recall() {
    for kind in SceneKind::ALL {
        let scene = render(kind, 512, 218).unwrap();
        // 1500 superpixels at 1024×436 have the same size as 375 at 512×218.
        let params = SlicParams {
            count: 375,
            ..SlicParams::default()
        };
        let sp = slic(&scene.frame1, &params).unwrap();
        check_segmentation(&sp, &scene.frame1, 375);
        let recall = boundary_recall(&sp.labels, &scene.depth1, 0.05, 2)
            .unwrap()
            .unwrap();
        println!(
            "{}: {} superpixels, boundary recall {recall:.3}",
            kind.name(),
            sp.len()
        );
        assert!(recall >= 0.9, "{}: boundary recall {recall}", kind.name());
    }
}

#[test]
fn graphs_are_consistent_with_the_labels() {
    let scene = render(SceneKind::Street, 256, 110).unwrap();
    let sp = slic(
        &scene.frame1,
        &SlicParams {
            count: 100,
            ..SlicParams::default()
        },
    )
    .unwrap();
    let g = boundary_graph(&sp, &scene.frame1);
    let adj = g.adjacency(sp.len());
    assert!(
        adj.iter().all(|a| !a.is_empty()),
        "every superpixel touches another"
    );
    for e in &g.edges {
        for &(p, q) in &e.pairs {
            assert_eq!(
                (sp.labels.data()[p as usize], sp.labels.data()[q as usize]),
                (e.a, e.b)
            );
        }
    }
    let knn = knn_graph(&sp, 15, 3.0);
    for (i, list) in knn.neighbours.iter().enumerate() {
        assert_eq!(list.len(), 15);
        assert!(
            list.iter()
                .all(|&(k, w)| k as usize != i && w > 0.0 && w <= 1.0)
        );
        assert!(
            list.windows(2).all(|p| p[0].1 >= p[1].1 - 1e-12),
            "nearest first"
        );
    }
}

#[test]
fn real_photo_segments_cleanly() {
    let Some(dir) = eval_case_dir("middlebury-motorcycle") else {
        eprintln!("skipping: the evaluation case middlebury-motorcycle is absent");
        return;
    };
    let case = read_case(&dir).unwrap();
    let sp = slic(&case.frame1, &SlicParams::default()).unwrap();
    check_segmentation(&sp, &case.frame1, 1500);
    let recall = boundary_recall(&sp.labels, case.depth1.as_ref().unwrap(), 0.05, 2)
        .unwrap()
        .unwrap();
    println!(
        "middlebury-motorcycle: {} superpixels, boundary recall {recall:.3}",
        sp.len()
    );
    // Measured 0.960 (README, Speed); the target is ≥ 0.9, as on the synthetic scenes.
    assert!(
        recall >= 0.9,
        "middlebury-motorcycle: boundary recall {recall}"
    );
}

#[test]
fn flat_image_still_gives_connected_superpixels() {
    let frame = Grid::filled(200, 100, [90u8, 90, 90]);
    let sp = slic(
        &frame,
        &SlicParams {
            count: 50,
            ..SlicParams::default()
        },
    )
    .unwrap();
    check_segmentation(&sp, &frame, 50);
}
