#![cfg(not(target_arch = "wasm32"))]
//! The synthetic scenes checked against themselves: the exact flow warps frame 2 onto frame 1,
//! depth plus camera motion reproduces the flow of the static world, and the masks say what each
//! scene is meant to contain.
// Tests make no results: the platform's maths functions are fine here (clippy.toml).
#![allow(clippy::disallowed_methods)]

use nalgebra::Vector3;
use superpixel_soup::eval::rigid_state;
use superpixel_soup::grid::Grid;
use superpixel_soup::synth::{SceneKind, SynthScene, render};

const W: usize = 256;
const H: usize = 110;

fn scene(kind: SceneKind) -> SynthScene {
    render(kind, W, H).unwrap()
}

/// True when (x, y) and its 8 neighbours have depths within 2 % of each other (no discontinuity).
fn smooth_depth(depth: &Grid<f32>, x: usize, y: usize) -> bool {
    let z = *depth.get(x, y);
    (-1..=1).all(|dy| {
        (-1..=1).all(|dx| {
            depth
                .get_checked(x as isize + dx, y as isize + dy)
                .is_some_and(|n| (n - z).abs() < 0.02 * z)
        })
    })
}

/// Bilinear sample of a colour frame at real coordinates.
fn sample(frame: &Grid<[u8; 3]>, x: f32, y: f32) -> [f32; 3] {
    let (x0, y0) = (x.floor() as usize, y.floor() as usize);
    let (fx, fy) = (x - x0 as f32, y - y0 as f32);
    let px = |xx: usize, yy: usize| {
        frame
            .get(xx.min(frame.width() - 1), yy.min(frame.height() - 1))
            .map(f32::from)
    };
    let (a, b, c, d) = (
        px(x0, y0),
        px(x0 + 1, y0),
        px(x0, y0 + 1),
        px(x0 + 1, y0 + 1),
    );
    [0, 1, 2].map(|k| {
        (a[k] * (1.0 - fx) + b[k] * fx) * (1.0 - fy) + (c[k] * (1.0 - fx) + d[k] * fx) * fy
    })
}

#[test]
fn flow_warps_frame2_onto_frame1_on_visible_pixels() {
    for kind in SceneKind::ALL {
        let s = scene(kind);
        let (mut sum, mut n) = (0.0f64, 0usize);
        for y in 1..H - 1 {
            for x in 1..W - 1 {
                if !*s.visible2.get(x, y) || !smooth_depth(&s.depth1, x, y) {
                    continue;
                }
                let [u, v] = *s.flow12.get(x, y);
                let (x2, y2) = (x as f32 + u, y as f32 + v);
                if x2 < 0.0 || y2 < 0.0 || x2 > (W - 1) as f32 || y2 > (H - 1) as f32 {
                    continue;
                }
                let warped = sample(&s.frame2, x2, y2);
                let orig = s.frame1.get(x, y).map(f32::from);
                sum += (0..3)
                    .map(|k| (warped[k] - orig[k]).abs() as f64)
                    .sum::<f64>()
                    / 3.0;
                n += 1;
            }
        }
        let mean = sum / n as f64;
        println!(
            "{}: mean |I1 − I2(x + f)| = {mean:.2} / 255 over {n} pixels",
            kind.name()
        );
        assert!(
            n > W * H / 3,
            "{}: too few visible pixels ({n})",
            kind.name()
        );
        assert!(mean < 6.0, "{}: warp error {mean:.2} / 255", kind.name());
    }
}

#[test]
fn depth_and_camera_motion_reproduce_the_static_flow_and_depth_in_camera_2() {
    for kind in SceneKind::ALL {
        let s = scene(kind);
        let k = s.intrinsics;
        let (mut worst, mut worst_z) = (0.0f64, 0.0f64);
        for y in 0..H {
            for x in 0..W {
                if *s.moving1.get(x, y) {
                    continue;
                }
                let z = *s.depth1.get(x, y) as f64;
                let r = k.ray(x as f64, y as f64);
                let p2 = s.camera_motion.apply([r[0] * z, r[1] * z, z]);
                let [u2, v2] = k.project(p2);
                let [fu, fv] = *s.flow12.get(x, y);
                worst = worst.max((u2 - x as f64 - fu as f64).hypot(v2 - y as f64 - fv as f64));
                worst_z = worst_z.max((*s.depth12.get(x, y) as f64 / p2[2] - 1.0).abs());
            }
        }
        assert!(
            worst < 2e-3,
            "{}: static flow off by {worst} px",
            kind.name()
        );
        assert!(
            worst_z < 1e-5,
            "{}: static depth in camera 2 off by {worst_z} (relative)",
            kind.name()
        );
    }
}

#[test]
fn every_pixel_has_depth_and_flow() {
    for kind in SceneKind::ALL {
        let s = scene(kind);
        assert!(
            s.depth1
                .data()
                .iter()
                .all(|z| z.is_finite() && *z > 0.5 && *z < 80.0),
            "{}",
            kind.name()
        );
        assert!(
            s.flow12
                .data()
                .iter()
                .all(|f| f[0].is_finite() && f[1].is_finite()),
            "{}",
            kind.name()
        );
        assert!(
            s.depth12.data().iter().all(|z| z.is_finite() && *z > 0.1),
            "{}: depth in camera 2",
            kind.name()
        );
    }
}

#[test]
fn the_crowd_s_scene_flow_moves_each_walker_rigidly() {
    // Every walker (and the static world) of the crowd is a rigid body: the 3D points of its
    // pixels at time 1 (depth1) and at time 2 (flow12 and depth12) differ by one rigid motion.
    let s = scene(SceneKind::Crowd);
    let k = s.intrinsics;
    let groups = 1 + *s.group1.data().iter().max().unwrap() as usize;
    let mut pairs = vec![Vec::new(); groups];
    for y in 0..H {
        for x in 0..W {
            let z1 = *s.depth1.get(x, y) as f64;
            let [u, v] = *s.flow12.get(x, y);
            let p1 = Vector3::from(k.ray(x as f64, y as f64)) * z1;
            let ray2 = k.ray(x as f64 + u as f64, y as f64 + v as f64);
            let p2 = Vector3::from(ray2) * *s.depth12.get(x, y) as f64;
            pairs[*s.group1.get(x, y) as usize].push((p1, p2));
        }
    }
    let mut fitted = 0;
    for (group, pairs) in pairs.iter().enumerate().filter(|(_, p)| p.len() >= 50) {
        let state = rigid_state(pairs).unwrap();
        let t = state.t_hat * state.lambda;
        let worst = (pairs.iter())
            .map(|(p, q)| (state.r * p + t - q).norm() / p.z)
            .fold(0.0, f64::max);
        assert!(
            worst < 1e-4,
            "group {group}: off a rigid motion by {worst} of the depth"
        );
        fitted += 1;
    }
    assert!(fitted >= 10, "only {fitted} groups with 50 pixels");
}

#[test]
fn scenes_contain_what_their_names_promise() {
    let share = |m: &Grid<bool>| m.data().iter().filter(|&&b| b).count() as f64 / m.len() as f64;
    let groups = |s: &SynthScene| {
        let mut g: Vec<u8> = s.group1.data().iter().copied().filter(|&g| g > 0).collect();
        g.sort();
        g.dedup();
        g.len()
    };
    let room = scene(SceneKind::StaticRoom);
    assert_eq!(share(&room.moving1), 0.0);
    let street = scene(SceneKind::Street);
    assert_eq!(groups(&street), 2);
    assert!(share(&street.moving1) > 0.02);
    let crowd = scene(SceneKind::Crowd);
    assert!(
        share(&crowd.moving1) > 0.5,
        "crowd moving share {}",
        share(&crowd.moving1)
    );
    assert!(groups(&crowd) >= 10);
    let flag = scene(SceneKind::Flag);
    assert_eq!(groups(&flag), 1);
    assert!(share(&flag.moving1) > 0.2);
    // The flag deforms: its flow is not one rigid image motion (spread of flow on the sheet).
    let sheet: Vec<f32> = flag
        .flow12
        .data()
        .iter()
        .zip(flag.moving1.data())
        .filter(|(_, m)| **m)
        .map(|(f, _)| f[0])
        .collect();
    let (lo, hi) = sheet
        .iter()
        .fold((f32::MAX, f32::MIN), |(a, b), &u| (a.min(u), b.max(u)));
    assert!(hi - lo > 1.0, "flag flow spread {lo}..{hi}");
    let group_share = |s: &SynthScene, g: u8| {
        s.group1.data().iter().filter(|&&x| x == g).count() as f64 / s.group1.len() as f64
    };
    // The creature (group 1) is big and close, with four walkers (groups 2–5) behind it
    // (measured: the creature covers 24.7 % of the view, all movers 36.2 %).
    let creature = scene(SceneKind::Creature);
    println!(
        "creature: moving {:.3}, creature {:.3}, groups {}",
        share(&creature.moving1),
        group_share(&creature, 1),
        groups(&creature)
    );
    assert_eq!(groups(&creature), 5);
    assert!(group_share(&creature, 1) > 0.2);
    // Road: the camera drives forward 0.28 m (static points come closer), five cars are in view
    // (10.6 % of the view).
    let road = scene(SceneKind::Road);
    println!(
        "road: moving {:.3}, groups {}",
        share(&road.moving1),
        groups(&road)
    );
    assert_eq!(groups(&road), 5);
    assert!(road.camera_motion.t[2] < -0.2);
    // Table: one box slides (5.3 % of the view); the camera both turns and moves, an orbit
    // rather than a pan (measured: 0.035 rad, 0.061 m).
    let table = scene(SceneKind::Table);
    let r = table.camera_motion.r;
    let angle = ((r[0][0] + r[1][1] + r[2][2] - 1.0) / 2.0)
        .clamp(-1.0, 1.0)
        .acos();
    let shift = table
        .camera_motion
        .t
        .iter()
        .map(|t| t * t)
        .sum::<f64>()
        .sqrt();
    println!(
        "table: moving {:.3}, groups {}, camera turn {angle:.4} rad, shift {shift:.4} m",
        share(&table.moving1),
        groups(&table)
    );
    assert_eq!(groups(&table), 1);
    assert!(share(&table.moving1) > 0.02);
    assert!(angle > 0.02 && shift > 0.04);
}

#[test]
fn flow_magnitudes_are_moderate_but_real() {
    for kind in SceneKind::ALL {
        let s = render(kind, 512, 218).unwrap();
        let mags: Vec<f32> = s.flow12.data().iter().map(|f| f[0].hypot(f[1])).collect();
        let max = mags.iter().fold(0.0f32, |a, &m| a.max(m));
        let mean = mags.iter().sum::<f32>() / mags.len() as f32;
        println!(
            "{}: flow mean {mean:.1} px, max {max:.1} px at 512×218",
            kind.name()
        );
        // At 1024×436 that is a mean of 3–30 px and at most ~60 px.
        assert!(
            mean > 1.5 && max < 30.0,
            "{}: mean {mean} max {max}",
            kind.name()
        );
    }
}

#[test]
fn bad_sizes_and_names_are_errors() {
    assert!(render(SceneKind::Flag, 8, 100).is_err());
    assert!(render(SceneKind::Flag, 100, 100_000).is_err());
    assert!(
        SceneKind::from_name("nope")
            .unwrap_err()
            .to_string()
            .contains("static-room")
    );
    assert_eq!(SceneKind::from_name("crowd").unwrap(), SceneKind::Crowd);
}
