//! The ground: the plane of the static world's floor, and how far a piece would lie under it.
//!
//! Things stand on the ground or above it; none is seen through it. So a pixel whose ray meets
//! the ground plane in front of the camera cannot be farther than the ground along that ray,
//! whatever moves. Two frames often leave a mover's scale free (a car driving ahead of the camera
//! is explained by the camera's own motion at a wrong, larger depth, and its contacts then glue
//! it to the far background), but placed too far it sinks under the road: this module measures
//! how far, and the scale solve ([`super::scales`]) charges for it.
//!
//! Conventions (docs/ARCHITECTURE.md): camera 1's frame, y down, a plane mᵀX = 1 at unit scale,
//! so a floor below the camera has m pointing down (m_y > 0) and meets the rays below its
//! horizon (mᵀx̄ > 0). Log-depths compare pieces at equal scale; the scale solve adds the
//! difference of their log-scales.

use nalgebra::{Matrix3, Vector3};

use super::{Piece, Soup};
use crate::camera::Intrinsics;
use crate::numeric::{cos, ln};
use crate::superpixels::Superpixels;

/// A plane counts as ground-like when its normal is within this angle of the camera's downward
/// axis (30°: floors and roads seen from a camera held roughly level, or tilted by up to 30°).
/// The contact terms use the same test through [`has_ground_like_plane`] (`scales::pair_weight`:
/// a piece standing on a ground-like one).
pub const GROUND_TILT_DEG: f64 = 30.0;

/// Whether the plane `m` (mᵀX = 1 in camera-1 coordinates, y down) is ground-like: it lies
/// below the camera (m_y > 0; a ceiling's m_y is negative) with its normal within
/// [`GROUND_TILT_DEG`] of the camera's downward axis.
pub fn is_ground_like(m: &Vector3<f64>) -> bool {
    m.y > cos(GROUND_TILT_DEG.to_radians()) * m.norm()
}

/// Whether `piece` has a ground-like plane ([`is_ground_like`]) of its own: a plane borrowed
/// from a neighbour ([`super::Piece::degenerate`]) is a guess, not a floor.
pub fn has_ground_like_plane(piece: &Piece) -> bool {
    piece.degenerate.is_none() && is_ground_like(&piece.m)
}

/// Two pieces lie on one ground plane when their anchors' log-depths differ by less than this
/// under it (5 %: the noise of well-measured planes, well below a kerb or a step).
const ON_PLANE_LOG_GAP: f64 = 0.05;

/// A ground-like plane is not the ground when more than [`MAX_UNDER_SHARE`] of the candidates'
/// pixels whose rays meet it lie more than this under it (log-depth; 0.2, the scale solve's
/// `sunk_gap`: farther than a piece straddling a contact with the floor reads).
const UNDER_LOG_GAP: f64 = 0.2;

/// The largest share of the candidates' pixels that may lie under the ground (see
/// [`UNDER_LOG_GAP`]): nothing is seen through the floor, so a plane with much of the static
/// world under it is a raised surface (a table top). Under the floor found on every evaluation
/// case 0–1.3 % of those pixels lie (FT3D's ground-like plane among floating things: 5.3 %);
/// under the table top that won the vote with quarter-resolution flow, 51 %.
const MAX_UNDER_SHARE: f64 = 0.15;

/// Every how many pixels of a piece the fit and the depth test look at (a superpixel has
/// hundreds; every fourth keeps the shape and costs a quarter).
const PIXEL_STRIDE: usize = 4;

/// The share of a piece's tested pixels that may lie deeper under the ground than its reported
/// depth below it. Half: a superpixel that straddles a thing's contact with the ground has
/// pixels of the ground below the contact line, where the thing's plane runs under the ground
/// (on the road, the 90th percentile put a car resting on it 0.28 under it at the truth), and a
/// piece's plane is least reliable at its far corners (small pieces near the horizon reached
/// 1–3 in log-depth under it there).
const BELOW_QUANTILE: f64 = 0.5;

/// A piece rests on the ground only where at least this many of its pixels sit directly above
/// ground pixels (fewer is a corner grazing the floor, whose plane is least reliable there).
pub const MIN_RESTING_PIXELS: usize = 3;

/// The ground plane of `soup`'s static world: among the `candidates` (pieces of one rigid
/// segment, so their unit-scale planes share a scale), those with a ground-like plane vote for
/// each other's planes by pixels; the plane with the most pixels within 5 % in depth
/// (`ON_PLANE_LOG_GAP`) is refitted to its voters' surface points twice. A plane with much of
/// the candidates' surface under it (`MAX_UNDER_SHARE`) is a raised surface, not the floor:
/// it and its voters drop out and the next plane by votes is tried. `None` when the ground's
/// pieces cover less than `min_share` of the image (no floor worth trusting is in view).
///
/// Returns m at the candidates' unit scale: depth z = 1 / (mᵀx̄).
pub fn ground_plane(
    soup: &Soup,
    superpixels: &Superpixels,
    intrinsics: &Intrinsics,
    candidates: &[bool],
    min_share: f64,
) -> Option<Vector3<f64>> {
    let ray = |[u, v]: [f64; 2]| Vector3::from(intrinsics.ray(u, v));
    // (piece, anchor ray) of every ground-like candidate.
    let ground_like: Vec<(usize, Vector3<f64>)> = soup
        .pieces
        .iter()
        .enumerate()
        .filter(|&(i, p)| candidates[i] && has_ground_like_plane(p))
        .map(|(i, _)| (i, ray(superpixels.segments[i].anchor)))
        .filter(|&(i, r)| soup.pieces[i].m.dot(&r) > 0.0)
        .collect();
    let on_plane = |m: &Vector3<f64>| -> Vec<usize> {
        ground_like
            .iter()
            .filter(|&&(i, r)| on_plane(m, &soup.pieces[i].m, &r))
            .map(|&(i, _)| i)
            .collect()
    };
    let pixels_of = |pieces: &[usize]| -> f64 {
        pieces
            .iter()
            .map(|&i| superpixels.segments[i].pixels.len() as f64)
            .sum()
    };
    // Candidates' planes by votes, most first (the later piece first on a tie).
    let mut order: Vec<(f64, usize)> = ground_like
        .iter()
        .map(|&(i, _)| (pixels_of(&on_plane(&soup.pieces[i].m)), i))
        .collect();
    order.sort_by(|a, b| b.0.total_cmp(&a.0).then(b.1.cmp(&a.1)));
    let mut dropped = vec![false; soup.pieces.len()];
    for (_, i) in order {
        if dropped[i] {
            continue;
        }
        dropped[i] = true;
        let mut m = Some(soup.pieces[i].m);
        for _ in 0..2 {
            m = m.and_then(|m| fit_plane(soup, superpixels, intrinsics, &on_plane(&m)));
        }
        let Some(m) = m else { continue };
        let voters = on_plane(&m);
        if under_share(soup, superpixels, intrinsics, candidates, &m) > MAX_UNDER_SHARE {
            voters.iter().for_each(|&j| dropped[j] = true);
            continue;
        }
        let total = superpixels.labels.width() * superpixels.labels.height();
        let share = pixels_of(&voters) / total.max(1) as f64;
        return (share >= min_share && is_ground_like(&m)).then_some(m);
    }
    None
}

/// The share of the `candidates`' pixels (every [`PIXEL_STRIDE`]-th, each on its own piece's
/// unit-scale plane) whose rays meet `m` ahead that lie more than [`UNDER_LOG_GAP`] under it
/// (0 when no ray meets it).
fn under_share(
    soup: &Soup,
    superpixels: &Superpixels,
    intrinsics: &Intrinsics,
    candidates: &[bool],
    m: &Vector3<f64>,
) -> f64 {
    let (mut under, mut met) = (0usize, 0usize);
    for i in (0..soup.pieces.len()).filter(|&i| candidates[i]) {
        for gap in gaps_under(soup, superpixels, intrinsics, m, i) {
            met += 1;
            under += usize::from(gap > UNDER_LOG_GAP);
        }
    }
    if met == 0 {
        0.0
    } else {
        under as f64 / met as f64
    }
}

/// The least-squares plane mᵀX = 1 through the unit-scale surface points of `pieces` (each
/// pixel on its own piece's plane, every [`PIXEL_STRIDE`]-th): Σ X Xᵀ m = Σ X. `None` without
/// a well-posed fit.
fn fit_plane(
    soup: &Soup,
    superpixels: &Superpixels,
    intrinsics: &Intrinsics,
    pieces: &[usize],
) -> Option<Vector3<f64>> {
    let width = superpixels.labels.width();
    let (mut xtx, mut xt1) = (Matrix3::zeros(), Vector3::zeros());
    for &i in pieces {
        let m = soup.pieces[i].m;
        for &p in superpixels.segments[i].pixels.iter().step_by(PIXEL_STRIDE) {
            let r = pixel_ray(intrinsics, width, p);
            let inv = m.dot(&r);
            if inv > 0.0 {
                let x = r / inv;
                xtx += x * x.transpose();
                xt1 += x;
            }
        }
    }
    let m = xtx.try_inverse()? * xt1;
    m.iter().all(|v| v.is_finite()).then_some(m)
}

/// Whether the unit-scale plane `m` lies on `ground` along `ray`: both in front of the camera,
/// their depths within `ON_PLANE_LOG_GAP` in log.
fn on_plane(ground: &Vector3<f64>, m: &Vector3<f64>, ray: &Vector3<f64>) -> bool {
    let (g, own) = (ground.dot(ray), m.dot(ray));
    g > 0.0 && own > 0.0 && (ln(g) - ln(own)).abs() < ON_PLANE_LOG_GAP
}

/// Whether pixel index `p` shows the ground: its piece is one of the static world's (`world`)
/// and lies on `ground` there ([`on_plane`]).
fn shows_ground(
    soup: &Soup,
    superpixels: &Superpixels,
    intrinsics: &Intrinsics,
    ground: &Vector3<f64>,
    world: &[bool],
    p: usize,
) -> bool {
    let labels = &superpixels.labels;
    let j = labels.data()[p] as usize;
    let ray = pixel_ray(intrinsics, labels.width(), p as u32);
    world[j] && on_plane(ground, &soup.pieces[j].m, &ray)
}

/// The normalised ray (z = 1) of pixel index `p` (y · width + x).
fn pixel_ray(intrinsics: &Intrinsics, width: usize, p: u32) -> Vector3<f64> {
    let p = p as usize;
    Vector3::from(intrinsics.ray((p % width) as f64, (p / width) as f64))
}

/// How far piece `i` lies under the ground at equal scale: the median (`BELOW_QUANTILE`),
/// over its pixels whose rays meet the ground ahead, of ln z̄_i − ln z̄_G (unit-scale depths of
/// the piece's plane and of `ground`). At log-scale s_i the piece lies that much plus s_i − s_G
/// under the ground (positive: under it). `None` when none of its rays meets both planes in
/// front of the camera (above the horizon).
pub fn depth_below_ground(
    soup: &Soup,
    superpixels: &Superpixels,
    intrinsics: &Intrinsics,
    ground: &Vector3<f64>,
    i: usize,
) -> Option<f64> {
    let mut below: Vec<f64> = gaps_under(soup, superpixels, intrinsics, ground, i).collect();
    if below.is_empty() {
        return None;
    }
    below.sort_by(f64::total_cmp);
    let k = ((below.len() - 1) as f64 * BELOW_QUANTILE).round() as usize;
    Some(below[k])
}

/// For every [`PIXEL_STRIDE`]-th pixel of piece `i` whose ray meets both its unit-scale plane
/// and `ground` in front of the camera, ln z̄_i − ln z̄_G: how far the piece lies under the
/// ground there at equal scale (positive: under it).
fn gaps_under<'a>(
    soup: &'a Soup,
    superpixels: &'a Superpixels,
    intrinsics: &'a Intrinsics,
    ground: &'a Vector3<f64>,
    i: usize,
) -> impl Iterator<Item = f64> + 'a {
    let width = superpixels.labels.width();
    let m = soup.pieces[i].m;
    superpixels.segments[i]
        .pixels
        .iter()
        .step_by(PIXEL_STRIDE)
        .filter_map(move |&p| {
            let r = pixel_ray(intrinsics, width, p);
            let (g, own) = (ground.dot(&r), m.dot(&r));
            (g > 0.0 && own > 0.0).then(|| ln(g) - ln(own))
        })
}

/// Where piece `i` rests on the ground: for each of its pixels p whose pixel below (p + width, so
/// any pixel on the piece's lower boundary, not only its bottom row) belongs to another piece of
/// the static world (`world`) that lies on `ground` there (within `ON_PLANE_LOG_GAP`), ln z̄_i(p) −
/// ln z̄_G(p): the log-depth of the piece's plane over that of the ground on the ray of p (the
/// pixel's centre, half a pixel above the contact: 0.004 in log-depth at the crowd's feet, more
/// just below the horizon), at equal scale (unit-scale planes, like [`depth_below_ground`]). At
/// log-scale s_i the piece's bottom then lies that much plus s_i − s_G behind the ground it rests
/// on. Empty for a piece with fewer than [`MIN_RESTING_PIXELS`] such pixels.
pub fn resting_gaps(
    soup: &Soup,
    superpixels: &Superpixels,
    intrinsics: &Intrinsics,
    ground: &Vector3<f64>,
    world: &[bool],
    i: usize,
) -> Vec<f64> {
    let width = superpixels.labels.width();
    let labels = superpixels.labels.data();
    let own = soup.pieces[i].m;
    let gaps: Vec<f64> = superpixels.segments[i]
        .pixels
        .iter()
        .filter_map(|&p| {
            let q = p as usize + width;
            let below_is_other = *labels.get(q)? as usize != i;
            if !(below_is_other && shows_ground(soup, superpixels, intrinsics, ground, world, q)) {
                return None;
            }
            // Both planes on the piece's own bottom pixel, where it would touch the ground.
            let ray = pixel_ray(intrinsics, width, p);
            let (g, here) = (ground.dot(&ray), own.dot(&ray));
            (g > 0.0 && here > 0.0).then(|| ln(g) - ln(here))
        })
        .collect();
    if gaps.len() < MIN_RESTING_PIXELS {
        Vec::new()
    } else {
        gaps
    }
}

/// The share of the image's bottom tenth of rows that shows the ground: pixels of the static
/// world's pieces (`world`) whose unit-scale planes lie on `ground` there (within
/// `ON_PLANE_LOG_GAP`). A floor that things stand on runs to the near edge of the view; a
/// ground-like plane found among floating things (FlyingThings3D) does not.
pub fn bottom_share(
    soup: &Soup,
    superpixels: &Superpixels,
    intrinsics: &Intrinsics,
    ground: &Vector3<f64>,
    world: &[bool],
) -> f64 {
    let labels = &superpixels.labels;
    let (width, height) = labels.size();
    if width == 0 || height == 0 {
        return 0.0;
    }
    let rows = (height / 10).max(1);
    let first = (height - rows) * width;
    let on_ground = (first..width * height)
        .filter(|&p| shows_ground(soup, superpixels, intrinsics, ground, world, p))
        .count();
    on_ground as f64 / (rows * width).max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Grid;
    use crate::soup::Piece;
    use crate::superpixels::Segment;

    const K: Intrinsics = Intrinsics {
        fx: 100.0,
        fy: 100.0,
        cx: 49.5,
        cy: 49.5,
    };

    /// Floor y = 2 (m = (0, ½, 0)): nothing, seen on the ray through pixel row v, lies deeper
    /// than 2 / ((v − cy) / fy) there.
    const FLOOR: Vector3<f64> = Vector3::new(0.0, 0.5, 0.0);

    /// A 100 × 100 image cut into 10 × 10-pixel superpixels; the rows of superpixels from
    /// `floor_from` down are on the floor, the rest on the wall z = 10 (m = (0, 0, 0.1)), all on
    /// the static world's motion (hypothesis 0), at one scale.
    fn room(floor_from: u32) -> (Soup, Superpixels) {
        let labels = Grid::from_fn(100, 100, |x, y| ((y / 10) * 10 + x / 10) as u32);
        let mut segments = Vec::new();
        let mut pieces = Vec::new();
        for j in 0..10u32 {
            for i in 0..10u32 {
                let pixels = (0..100u32)
                    .map(|p| (10 * j + p / 10) * 100 + 10 * i + p % 10)
                    .collect();
                segments.push(Segment {
                    pixels,
                    anchor: [4.5 + 10.0 * i as f64, 4.5 + 10.0 * j as f64],
                    mean_lab: [0.0; 3],
                    mean_rgb: [0; 3],
                    bbox: [10 * i, 10 * j, 10 * i + 9, 10 * j + 9],
                });
                let m = if j >= floor_from {
                    FLOOR
                } else {
                    Vector3::new(0.0, 0.0, 0.1)
                };
                pieces.push(Piece {
                    r: Matrix3::identity(),
                    t_hat: Vector3::new(1.0, 0.0, 0.0),
                    m,
                    lambda: 1.0,
                    hypothesis: 0,
                    degenerate: None,
                });
            }
        }
        let soup = Soup {
            pieces,
            hypotheses: Vec::new(),
            noise_px: 0.0,
            ego_rival: None,
            rugged_to_ego: 0,
        };
        (soup, Superpixels { labels, segments })
    }

    #[test]
    fn the_floor_is_found_where_it_covers_enough_of_the_image() {
        let (soup, sp) = room(6);
        let all = vec![true; soup.pieces.len()];
        let m = ground_plane(&soup, &sp, &K, &all, 0.3).expect("a floor of 40 %");
        assert!((m - FLOOR).norm() < 1e-9, "{m}");
        // 40 % of the image is not enough where half is asked for.
        assert_eq!(ground_plane(&soup, &sp, &K, &all, 0.5), None);
        // Only the candidates vote: without the floor's pieces there is no ground.
        let walls: Vec<bool> = soup.pieces.iter().map(|p| p.m != FLOOR).collect();
        assert_eq!(ground_plane(&soup, &sp, &K, &walls, 0.01), None);
    }

    #[test]
    fn a_raised_surface_with_the_floor_under_it_is_not_the_ground() {
        // A table top y = 1 (m = (0, 1, 0)) on the rows of superpixels 5–7 outvotes the floor
        // y = 2 on rows 8–9 (30 % of the image against 20 %), but the floor lies under it by
        // ln 2 on every ray: 20 of the 50 rows whose rays meet it.
        let table = Vector3::new(0.0, 1.0, 0.0);
        let (mut soup, sp) = room(8);
        for (i, piece) in soup.pieces.iter_mut().enumerate() {
            if (50..80).contains(&i) {
                piece.m = table;
            }
        }
        let all = vec![true; soup.pieces.len()];
        let m = ground_plane(&soup, &sp, &K, &all, 0.1).expect("the floor");
        assert!((m - FLOOR).norm() < 1e-9, "{m}");
        // Without the floor's pieces among the candidates the table top is the ground.
        let no_floor: Vec<bool> = soup.pieces.iter().map(|p| p.m != FLOOR).collect();
        let m = ground_plane(&soup, &sp, &K, &no_floor, 0.1).expect("the table top");
        assert!((m - table).norm() < 1e-9, "{m}");
    }

    #[test]
    fn a_plane_of_its_own_below_the_camera_is_ground_like_and_a_ceiling_or_a_borrowed_one_is_not() {
        let (soup, _) = room(6);
        let floor = *soup
            .pieces
            .iter()
            .find(|p| p.m == FLOOR)
            .expect("the room has a floor");
        assert!(has_ground_like_plane(&floor));
        // The ceiling y = −2: as level as the floor, but above the camera.
        let ceiling = Piece { m: -FLOOR, ..floor };
        assert!(!has_ground_like_plane(&ceiling));
        // The wall z = 10 faces the camera.
        assert!(!has_ground_like_plane(&Piece {
            m: Vector3::new(0.0, 0.0, 0.1),
            ..floor
        }));
        // The floor's plane carried over from a neighbour is a guess.
        let borrowed = Piece {
            degenerate: Some(crate::soup::Degeneracy::TooFewPixels),
            ..floor
        };
        assert!(!has_ground_like_plane(&borrowed));
        // Tilted by 25° it still counts, by 35° not (`GROUND_TILT_DEG`).
        for (deg, counts) in [(25.0f64, true), (35.0, false)] {
            let a = deg.to_radians();
            assert_eq!(
                is_ground_like(&Vector3::new(0.0, a.cos(), a.sin())),
                counts,
                "{deg}°"
            );
        }
    }

    #[test]
    fn a_floor_tilted_within_thirty_degrees_counts_and_a_wall_does_not() {
        for (deg, found) in [(25.0f64, true), (35.0, false)] {
            let (mut soup, sp) = room(6);
            let a = deg.to_radians();
            // The floor's normal turned by `a` about the camera's x axis, 2 below the camera.
            let tilted = Vector3::new(0.0, a.cos(), a.sin()) / 2.0;
            for p in soup.pieces.iter_mut().filter(|p| p.m == FLOOR) {
                p.m = tilted;
            }
            // Only the floor's pieces are candidates: the wall z = 10 would lie under a floor
            // that rises towards it (the test's room is not built to be seen tilted).
            let floor: Vec<bool> = soup.pieces.iter().map(|p| p.m == tilted).collect();
            let m = ground_plane(&soup, &sp, &K, &floor, 0.1);
            assert_eq!(m.is_some(), found, "{deg}°: {m:?}");
            if let Some(m) = m {
                assert!((m - tilted).norm() < 1e-9);
            }
        }
    }

    #[test]
    fn the_depth_below_ground_is_the_log_ratio_at_the_median_pixel() {
        let (soup, sp) = room(6);
        // A piece of the floor lies on it.
        let floor_piece = 7 * 10 + 3;
        let on = depth_below_ground(&soup, &sp, &K, &FLOOR, floor_piece).unwrap();
        assert!(on.abs() < 1e-12, "{on}");
        // A wall piece in the floor's rows (the wall z = 10 continued below the horizon) lies
        // under the floor. Its tested pixels are every fourth of rows 70–79, the median one in
        // row 74, whose ray meets the floor at depth 2 / ((74 − 49.5) / 100) ≈ 8.16: under it
        // by ln(10 / 8.16).
        let (mut sunk, _) = room(6);
        sunk.pieces[floor_piece].m = Vector3::new(0.0, 0.0, 0.1);
        let below = depth_below_ground(&sunk, &sp, &K, &FLOOR, floor_piece).unwrap();
        let expected = (10.0 * 0.5 * (74.0 - 49.5) / 100.0f64).ln();
        assert!(
            (below - expected).abs() < 1e-9,
            "{below} against {expected}"
        );
        // Above the horizon no ray meets the floor.
        assert_eq!(depth_below_ground(&soup, &sp, &K, &FLOOR, 2 * 10 + 3), None);
    }
    #[test]
    fn a_piece_standing_on_the_floor_rests_on_it_at_its_bottom_row() {
        let (mut soup, sp) = room(6);
        let world = vec![true; soup.pieces.len()];
        // Piece 53 (row 5, just above the floor's rows) as a mover's upright face at depth z.
        // Its bottom pixels (row 59) sit on the floor's piece 63; the floor on their rays lies
        // at 2 / ((59 − 49.5) / 100), so the gap is ln(z (59 − 49.5) / 200).
        let z = 30.0;
        soup.pieces[53].m = Vector3::new(0.0, 0.0, 1.0 / z);
        soup.pieces[53].hypothesis = 1;
        let gaps = resting_gaps(&soup, &sp, &K, &FLOOR, &world, 53);
        assert_eq!(gaps.len(), 10, "one per pixel of the bottom row");
        let expected = (z * (59.0 - 49.5) / 200.0f64).ln();
        for g in &gaps {
            assert!((g - expected).abs() < 1e-9, "{g} against {expected}");
        }
        // Only the static world's pieces on the ground carry it: not when the piece below is
        // no world piece, nor where that piece does not lie on the ground.
        let mut not_world = world.clone();
        not_world[63] = false;
        assert!(resting_gaps(&soup, &sp, &K, &FLOOR, &not_world, 53).is_empty());
        let mut lifted = soup.clone();
        lifted.pieces[63].m = FLOOR * 1.2;
        assert!(resting_gaps(&lifted, &sp, &K, &FLOOR, &world, 53).is_empty());
        // A piece above a wall piece rests on nothing.
        assert!(resting_gaps(&soup, &sp, &K, &FLOOR, &world, 43).is_empty());
    }

    #[test]
    fn the_bottom_share_is_the_ground_seen_along_the_bottom_rows() {
        let (soup, sp) = room(6);
        let all = vec![true; soup.pieces.len()];
        assert_eq!(bottom_share(&soup, &sp, &K, &FLOOR, &all), 1.0);
        // Not the static world's: not the ground.
        let none = vec![false; soup.pieces.len()];
        assert_eq!(bottom_share(&soup, &sp, &K, &FLOOR, &none), 0.0);
        // Three of the ten bottom pieces on the wall instead: 70 % of the bottom rows.
        let mut wall = soup.clone();
        for i in [90, 91, 92] {
            wall.pieces[i].m = Vector3::new(0.0, 0.0, 0.1);
        }
        let share = bottom_share(&wall, &sp, &K, &FLOOR, &all);
        assert!((share - 0.7).abs() < 1e-12, "{share}");
    }
}
