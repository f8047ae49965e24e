//! The soup: ARAP scales on a hand-built soup, end-to-end accuracy on synthetic scenes with
//! exact flow, and the no-parallax errors.
#![cfg(not(target_arch = "wasm32"))]

use nalgebra::{Matrix3, Vector3};
use superpixel_soup::camera::Intrinsics;
use superpixel_soup::eval::depth_metrics;
use superpixel_soup::geometry::essential::Motion;
use superpixel_soup::grid::Grid;
use superpixel_soup::image::{ExifInfo, Frame, LoadedImage};
use superpixel_soup::input::prepare_pair;
use superpixel_soup::soup::arap::{ArapReport, ScaleInputs, ScaleParams, solve_scales};
use superpixel_soup::soup::{Piece, Soup};
use superpixel_soup::superpixels::graph::{BoundaryGraph, knn_graph};
use superpixel_soup::superpixels::{Segment, Superpixels};
use superpixel_soup::synth::{SceneKind, render};
use superpixel_soup::{Error, FlowInput, Params, reconstruct};

const K: Intrinsics = Intrinsics {
    fx: 100.0,
    fy: 100.0,
    cx: 50.0,
    cy: 50.0,
};

/// A 10 × 10 grid of superpixels on the plane z = 10: the left half (body A) is static while the
/// camera moves by t_A; the right half (body B) moves on its own, so its relative motion is
/// t_B = t_A + δ. Each piece is given at unit scale (depths divided by ‖t‖), as the unorganised
/// soup has them. Returns the soup and the superpixels (anchors only).
fn two_body_soup(delta: Vector3<f64>) -> (Soup, Superpixels) {
    let t_a = Vector3::new(1.0, 0.0, 0.0);
    let t_b = t_a + delta;
    let mut segments = Vec::new();
    let mut pieces = Vec::new();
    for j in 0..10 {
        for i in 0..10 {
            let anchor = [5.0 + 10.0 * i as f64, 5.0 + 10.0 * j as f64];
            segments.push(Segment {
                pixels: vec![0],
                anchor,
                mean_lab: [0.0; 3],
                mean_rgb: [0; 3],
                bbox: [0, 0, 0, 0],
            });
            let (t, h) = if i < 5 { (t_a, 0) } else { (t_b, 1) };
            // True plane z = 10 → m = (0, 0, 0.1); at unit scale depths shrink by ‖t‖: m · ‖t‖.
            pieces.push(Piece {
                r: Matrix3::identity(),
                t_hat: t.normalize(),
                m: Vector3::new(0.0, 0.0, 0.1 * t.norm()),
                lambda: 1.0,
                hypothesis: h,
                degenerate: None,
            });
        }
    }
    let hypotheses = vec![
        Motion {
            r: Matrix3::identity(),
            t: t_a.normalize(),
        },
        Motion {
            r: Matrix3::identity(),
            t: t_b.normalize(),
        },
    ];
    let sp = Superpixels {
        labels: Grid::filled(100, 100, 0),
        segments,
    };
    (Soup { pieces, hypotheses }, sp)
}

/// [`two_body_soup`] with its scales solved by `params` from the K-NN (ARAP) terms alone (no
/// touching boundaries), and the solve's report.
fn solve_two_bodies(delta: Vector3<f64>, params: &ScaleParams) -> (Soup, ArapReport) {
    let (mut soup, sp) = two_body_soup(delta);
    let knn = knn_graph(&sp, 8, 3.0);
    let boundaries = BoundaryGraph { edges: Vec::new() };
    let flow = Grid::filled(100, 100, [0.0f32, 0.0]);
    let inputs = ScaleInputs {
        superpixels: &sp,
        knn: &knn,
        boundaries: &boundaries,
        flow: &flow,
        intrinsics: &K,
    };
    let report = solve_scales(&mut soup, &inputs, params);
    (soup, report)
}

#[test]
fn arap_recovers_the_relative_scale_of_two_bodies() {
    // Body B drifts slightly towards the camera while the camera translates sideways.
    let delta = Vector3::new(0.0, 0.0, -0.3);
    let (soup, report) = solve_two_bodies(delta, &ScaleParams::default());
    let (a, b) = (&soup.pieces[..], &soup.pieces[5..]);
    let lambda_a: Vec<f64> = (0..10)
        .flat_map(|j| (0..5).map(move |i| j * 10 + i))
        .map(|i| a[i].lambda)
        .collect();
    let lambda_b: Vec<f64> = (0..10)
        .flat_map(|j| (0..5).map(move |i| j * 10 + i))
        .map(|i| b[i].lambda)
        .collect();
    let spread = |v: &[f64]| {
        v.iter().cloned().fold(0.0, f64::max) / v.iter().cloned().fold(f64::INFINITY, f64::min)
    };
    assert!(
        spread(&lambda_a) < 1.01 && spread(&lambda_b) < 1.01,
        "one scale per rigid body"
    );
    let ratio = lambda_b[0] / lambda_a[0];
    let truth = (Vector3::new(1.0, 0.0, 0.0) + delta).norm();
    println!(
        "λ_B / λ_A = {ratio:.4} (truth {truth:.4}), energy {:.4} → {:.4}",
        report.energy_start, report.energy_end
    );
    assert!(
        (ratio / truth - 1.0).abs() < 0.05,
        "ratio {ratio} vs {truth}"
    );
    assert!(report.energy_end <= report.energy_start);
    let total: f64 = soup.pieces.iter().map(|p| p.lambda).sum();
    assert!((total - 1.0).abs() < 1e-9);
}

fn pair_of(a: &Frame, b: &Frame, k: Intrinsics) -> superpixel_soup::input::FramePair {
    let l = |f: &Frame| LoadedImage {
        frame: f.clone(),
        exif: ExifInfo::default(),
    };
    prepare_pair(l(a), l(b), Some(k), 1024).unwrap()
}

#[test]
fn synthetic_scenes_with_exact_flow() {
    // The product's working size and defaults (smaller sizes are worse: the street at 512×218 with
    // 400 superpixels assigns the cars' superpixels less reliably).
    let params = Params::default();
    for (kind, bound) in [(SceneKind::StaticRoom, 0.005), (SceneKind::Street, 0.03)] {
        let s = render(kind, 1024, 436).unwrap();
        let rec = reconstruct(
            &pair_of(&s.frame1, &s.frame2, s.intrinsics),
            FlowInput::Given(s.flow12.clone()),
            &params,
            &mut |_, _| {},
        )
        .unwrap();
        let m = depth_metrics(&s.depth1, &rec.depth_input).unwrap();
        println!(
            "{}: MRE {:.4}, coverage {:.3}",
            kind.name(),
            m.mre,
            m.coverage
        );
        assert!(m.mre < bound, "{}: MRE {}", kind.name(), m.mre);
        assert!(m.coverage > 0.95);
        assert_eq!(rec.cloud1.positions.len(), rec.cloud2.positions.len());
        // Frame 2's points project where the flow says: X' = X + scene flow lands on x + f(x).
        let k = rec.report.camera.intrinsics;
        let mut errors: Vec<f64> = Vec::new();
        for y in (0..rec.depth.height()).step_by(7) {
            for x in (0..rec.depth.width()).step_by(7) {
                let z = *rec.depth.get(x, y) as f64;
                let d = rec.scene_flow.get(x, y);
                if !z.is_finite() || !d[0].is_finite() {
                    continue;
                }
                let p = Vector3::from(k.ray(x as f64, y as f64)) * z;
                let q = p + Vector3::new(d[0] as f64, d[1] as f64, d[2] as f64);
                let [u, v] = k.project([q.x, q.y, q.z]);
                let f = rec.flow.get(x, y);
                errors.push((u - x as f64 - f[0] as f64).hypot(v - y as f64 - f[1] as f64));
            }
        }
        errors.sort_by(f64::total_cmp);
        let median = errors[errors.len() / 2];
        assert!(
            median < 0.5,
            "{}: median reprojection {median} px",
            kind.name()
        );
        assert!(rec.report.arap.energy_end <= rec.report.arap.energy_start);
    }
}

#[test]
fn identical_frames_and_pure_rotation_have_no_parallax() {
    let s = render(SceneKind::StaticRoom, 256, 110).unwrap();
    let params = Params {
        superpixels: superpixel_soup::superpixels::SlicParams {
            count: 100,
            ..Default::default()
        },
        ..Params::default()
    };
    let zero = Grid::filled(256, 110, [0.0f32, 0.0]);
    let err = reconstruct(
        &pair_of(&s.frame1, &s.frame1, s.intrinsics),
        FlowInput::Given(zero),
        &params,
        &mut |_, _| {},
    )
    .unwrap_err();
    assert!(matches!(err, Error::NoParallax(_)), "{err}");
    assert!(
        err.to_string()
            .contains("no parallax: depth cannot be recovered")
    );
    // A camera turning on the spot: the flow of a rotation R is x' ~ K R K⁻¹ x.
    let r = nalgebra::Rotation3::from_euler_angles(0.01, 0.02, 0.0).into_inner();
    let k = s.intrinsics;
    let rotation_flow = Grid::from_fn(256, 110, |x, y| {
        let p = r * Vector3::from(k.ray(x as f64, y as f64));
        let [u, v] = k.project([p.x, p.y, p.z]);
        [(u - x as f64) as f32, (v - y as f64) as f32]
    });
    let err = reconstruct(
        &pair_of(&s.frame1, &s.frame2, k),
        FlowInput::Given(rotation_flow),
        &params,
        &mut |_, _| {},
    )
    .unwrap_err();
    assert!(matches!(err, Error::NoParallax(_)), "{err}");
}

#[test]
fn scale_band_is_centred_on_equal_median_depths() {
    // Body B moves almost with the camera: its unit-scale depths come out 20 times those of
    // body A although both lie on z = 10 (true depth ratio 1). The ARAP energy alone favours
    // equal unit scales, i.e. a depth ratio near 20; the band must bound the ratio of the two
    // bodies' median depths, not of their unit scales, so for every band width b the solved
    // depth ratio lies in [1/b, b] (a band on unit scales would leave it at 20/b or more).
    // Measured: the solve stops on the band's edge (ratio b), not at the true ratio 1.
    for band in [2.0, 4.0] {
        let params = ScaleParams {
            band,
            ..ScaleParams::default()
        };
        let (soup, _) = solve_two_bodies(Vector3::new(-0.95, 0.0, 0.0), &params);
        let ray = Vector3::new(0.0, 0.0, 1.0);
        let ratio = soup.pieces[5].depth(&ray) / soup.pieces[0].depth(&ray);
        println!("band {band}: depth ratio B / A = {ratio:.4}");
        assert!(
            (1.0 / band - 1e-9..=band + 1e-9).contains(&ratio),
            "band {band}: depth ratio {ratio} outside the band"
        );
    }
}
