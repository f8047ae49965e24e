//! Refinement of planes, motions and scales together: the paper's section 5 (eq. 3, 4, 6),
//! solved by max-product particle belief propagation (MP-PBP) with TRW-S.
//!
//! Each piece's state θ_i = (R_i, t_i = λ_i t̂_i, plane m_i / λ_i) has 9 degrees of freedom. The
//! energy is
//!
//! E(θ) = w_proj Σ_i E_proj(θ_i) + Σ_(a,b touching) E_cont(θ_a, θ_b) + Σ_i E_ground(θ_i)
//!
//! - E_proj: the mean planar transfer error (px, capped) of the piece's reliable flow under its
//!   homography K (R + t mᵀ) K⁻¹; scale-free, and 0 for a piece without reliable flow (its state
//!   then comes from its neighbours).
//! - E_cont: for the boundary pixel pairs of a and b (subsampled), on the ray r through each
//!   pair's midpoint, the truncated log-depth gaps of [`scales::gaps`] (frame 1: both planes'
//!   depths on r; frame 2: how far each moved point lies off the other's moved plane), with the
//!   same pair weights as the scale solve ([`super::scales`]); a state behind either camera
//!   pays the full truncation.
//! - E_ground: `ground_weight` broken contacts for a piece whose anchor lies more than σ under
//!   the static world's ground plane ([`super::ground`], at the median scale of the world's
//!   well-measured pieces): nothing is seen through the floor, as in the scale solve.
//!
//! Each iteration draws P particles per piece — its current state (particle 0, so the energy
//! never rises), the current states of its touching neighbours (the moves that matter most:
//! a piece adopts a neighbour's plane and motion; a piece without flow also gets each
//! neighbour's motion with a camera-facing plane at their boundary's depth), and Gaussian
//! perturbations of its scale and plane that shrink over the iterations — tabulates the unary
//! and the P×P pairwise costs, and takes the TRW-S labelling when it lowers E. After each
//! iteration the median scale is reset to 1 (E ignores the global scale). At the end, a depth
//! tail control gives pieces placed more than `max_depth_ratio` from the median depth a
//! neighbour's motion and a camera-facing plane at their shared boundary's depth.

use nalgebra::Vector3;
use serde::Serialize;

use super::ground;
use super::init::sample_correspondences;
use super::plane::mean_transfer_px;
use super::scales::{
    self, RayPoint, ScaleInputs, ScaleParams, TruncatedGaps, pair_weight, sampled_pairs,
};
use super::{Piece, Soup};
use crate::geometry::essential::Motion;
use crate::mrf::trws::{Mrf, TrwsOptions, trws};
use crate::numeric::{exp, ln};
use crate::rng::Rng;

/// Settings of the refinement.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct RefineParams {
    /// MP-PBP iterations (0 turns the refinement off). 6 is within a few % of 12 (measured).
    pub iterations: usize,
    /// Particles per piece and iteration (the paper uses 50; 16 is within 10 % in energy).
    pub particles: usize,
    /// Weight of E_proj (per px of mean transfer error) against the contact terms (each touching
    /// pair weighs 1 in total, so at most 2σ in both frames): 0.3 lets a piece trade a third of
    /// a pixel of fit for one contact (measured: 0.2–0.5 give similar MREs, 1 and 3 glue fewer
    /// wrong pieces back to their neighbours).
    pub proj_weight: f64,
    /// Transfer errors are capped at this (px) in E_proj.
    pub cap_px: f64,
    /// Reliable-flow samples per piece for E_proj.
    pub samples: usize,
    /// Standard deviation of the first iteration's log-scale perturbations; halves each iteration.
    pub scale_spread: f64,
    /// Standard deviation of the first iteration's relative plane perturbations; halves each
    /// iteration.
    pub plane_spread: f64,
    /// TRW-S passes per iteration.
    pub trws_passes: usize,
    /// Tail control after the refinement: a piece whose depth at its anchor is more than this
    /// factor from the median piece depth (either way) takes the state of the touching piece
    /// nearest that median. Depths 30× beyond the median move less than 1/30 of the scene's
    /// parallax (below flow noise on most pairs), so nothing in the data placed them there.
    pub max_depth_ratio: f64,
    /// The ground in the refinement: a piece whose anchor lies more than σ under the static
    /// world's ground plane (see [`super::ground`]) pays this many broken contacts (2σ each).
    /// The scale solve lifts movers out of the ground; without this a piece could adopt a
    /// neighbour's plane that sinks it again (the street with preset medium: one piece 4.6×
    /// too deep held a fifth of the error). 0 switches it off.
    pub ground_weight: f64,
    /// Seed of the perturbations.
    pub seed: u64,
}

impl Default for RefineParams {
    fn default() -> Self {
        RefineParams {
            iterations: 6,
            particles: 16,
            proj_weight: 0.3,
            cap_px: 3.0,
            samples: 32,
            scale_spread: 0.2,
            plane_spread: 0.05,
            trws_passes: 10,
            max_depth_ratio: 30.0,
            ground_weight: 3.0,
            seed: 2017,
        }
    }
}

impl RefineParams {
    /// The paper's setting: 50 particles, 10 iterations.
    pub fn paper() -> Self {
        RefineParams {
            iterations: 10,
            particles: 50,
            ..RefineParams::default()
        }
    }
}

/// What the refinement did.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RefineReport {
    /// E before the first iteration and after each.
    pub energies: Vec<f64>,
    /// TRW-S lower bound of each iteration's particle MRF.
    pub lower_bounds: Vec<f64>,
    /// Pieces moved by the depth tail control.
    pub tail_pieces: usize,
}

/// One touching pair of pieces and the rays and weights of its sampled boundary pairs.
struct Contact {
    a: usize,
    b: usize,
    rays: Vec<Vector3<f64>>,
    weights: Vec<f64>,
}

/// The refinement problem: per piece its flow samples, per touching pair its contact rays.
pub struct Problem {
    samples: Vec<Vec<crate::geometry::Correspondence>>,
    /// Normalised rays through each piece's anchor and the corners of its bounding box.
    extent_rays: Vec<[Vector3<f64>; 5]>,
    contacts: Vec<Contact>,
    /// Per piece, its touching pieces and the index of the contact with each.
    neighbours: Vec<Vec<(usize, usize)>>,
    focal: f64,
    /// The contact costs at the scale solve's σ.
    truncation: TruncatedGaps,
    /// The static world's ground, if one is in view.
    ground: Option<Ground>,
    params: RefineParams,
}

/// The static world's ground plane and what carries its scale.
struct Ground {
    /// The plane at the unit scale of the ego-motion (depth 1 / (mᵀx̄)), fitted by
    /// [`ground::ground_plane`] to the well-measured pieces of the static world.
    plane: Vector3<f64>,
    /// Those pieces: the ground lies at their median scale λ.
    world: Vec<usize>,
}

impl Ground {
    /// The ground's scale in `soup`: the median λ of the world pieces.
    fn scale(&self, soup: &Soup) -> f64 {
        let mut lambdas: Vec<f64> = self.world.iter().map(|&i| soup.pieces[i].lambda).collect();
        lambdas.sort_by(f64::total_cmp);
        lambdas.get(lambdas.len() / 2).copied().unwrap_or(1.0)
    }
}

/// Where each of `states` meets each of `rays`, ray by ray: element `r · states.len() + k` is
/// state k on ray r, all NaN where that point is behind a camera.
fn ray_columns(states: &[Piece], rays: &[Vector3<f64>]) -> Vec<RayPoint> {
    let behind = RayPoint {
        log_depth: f64::NAN,
        moved: Vector3::repeat(f64::NAN),
        plane2: Vector3::repeat(f64::NAN),
    };
    rays.iter()
        .flat_map(|r| {
            states
                .iter()
                .map(move |s| scales::ray_point(s, r).unwrap_or(behind))
        })
        .collect()
}

impl Problem {
    /// Builds the problem for `soup` (its pair weights from its current planes and the flow).
    pub fn new(
        soup: &Soup,
        inputs: &ScaleInputs,
        scale_params: &ScaleParams,
        params: &RefineParams,
    ) -> Self {
        let sp = inputs.superpixels;
        let k = inputs.intrinsics;
        let samples = sample_correspondences(sp, inputs.flow, inputs.reliable, k, params.samples);
        let mut contacts = Vec::new();
        let mut neighbours = vec![Vec::new(); soup.pieces.len()];
        for edge in inputs
            .boundaries
            .edges
            .iter()
            .filter(|e| !e.pairs.is_empty())
        {
            let (a, b) = (edge.a as usize, edge.b as usize);
            let mut rays = Vec::new();
            let mut weights = Vec::new();
            for (j, ray) in sampled_pairs(edge, inputs, scale_params) {
                rays.push(ray);
                weights.push(pair_weight(soup, inputs, scale_params, edge, j));
            }
            let total = weights.len() as f64;
            weights.iter_mut().for_each(|w| *w /= total);
            neighbours[a].push((b, contacts.len()));
            neighbours[b].push((a, contacts.len()));
            contacts.push(Contact {
                a,
                b,
                rays,
                weights,
            });
        }
        let world = scales::world_pieces(soup, inputs, scale_params.world_parallax);
        let ground = (params.ground_weight > 0.0 && scale_params.ground_weight > 0.0)
            .then(|| ground::ground_plane(soup, sp, k, &world, scale_params.ground_share))
            .flatten()
            .map(|plane| Ground {
                plane,
                world: (0..world.len()).filter(|&i| world[i]).collect(),
            });
        Problem {
            ground,
            extent_rays: sp
                .segments
                .iter()
                .map(|s| {
                    let [x0, y0, x1, y1] = s.bbox.map(f64::from);
                    let ray = |x: f64, y: f64| Vector3::from(k.ray(x, y));
                    [
                        ray(s.anchor[0], s.anchor[1]),
                        ray(x0, y0),
                        ray(x1, y0),
                        ray(x0, y1),
                        ray(x1, y1),
                    ]
                })
                .collect(),
            samples,
            contacts,
            neighbours,
            focal: 0.5 * (k.fx + k.fy),
            truncation: TruncatedGaps::new(scale_params.sigma),
            params: *params,
        }
    }

    /// The median frame-1 depth of `state` on the rays of contact `c` (NaN without one).
    fn boundary_depth(&self, state: &Piece, c: usize) -> f64 {
        let mut z: Vec<f64> = self.contacts[c]
            .rays
            .iter()
            .map(|r| state.depth(r))
            .filter(|z| z.is_finite() && *z > 0.0)
            .collect();
        z.sort_by(f64::total_cmp);
        z.get(z.len() / 2).copied().unwrap_or(f64::NAN)
    }

    /// w_proj E_proj of piece `i` in state `piece`.
    fn unary(&self, i: usize, piece: &Piece) -> f64 {
        let samples = &self.samples[i];
        if samples.is_empty() {
            return 0.0;
        }
        // The homography R + t mᵀ does not depend on λ: unit translation and unit-scale plane.
        let motion = Motion {
            r: piece.r,
            t: piece.t_hat,
        };
        let cost = mean_transfer_px(samples, &motion, &piece.m, self.focal, self.params.cap_px);
        self.params.proj_weight * cost
    }

    /// The ground's cost of piece `i` in state `piece` with the ground at scale `ground_scale`
    /// ([`Ground::scale`]): `ground_weight` broken contacts where its anchor lies more than σ
    /// under the ground, 0 above the horizon or without a ground.
    fn ground_cost(&self, i: usize, piece: &Piece, ground_scale: f64) -> f64 {
        let Some(ground) = &self.ground else {
            return 0.0;
        };
        let ray = &self.extent_rays[i][0];
        let inv = ground.plane.dot(ray);
        let z = piece.depth(ray);
        let sigma = self.truncation.sigma();
        // z / z_ground = z (mᵀx̄) / λ_ground.
        if inv > 0.0 && z * inv / ground_scale > exp(sigma) {
            self.params.ground_weight * 2.0 * sigma
        } else {
            0.0
        }
    }

    /// The E_cont table of contact `c` between the states `a` of its piece `c.a` and `b` of
    /// `c.b`: element `i · b.len() + j` is E_cont(a[i], b[j]). The loops run over `b` innermost
    /// on columns without `Option`s (a state behind a camera on a ray is NaN there and pays σ in
    /// both frames through the comparisons of [`TruncatedGaps::costs`]), so they compile without
    /// branches: this table is most of the refinement's time.
    fn contact_table(&self, c: &Contact, a: &[Piece], b: &[Piece]) -> Vec<f64> {
        let full = 2.0 * self.truncation.sigma();
        let columns = ray_columns(b, &c.rays);
        let n = b.len();
        let mut table = vec![0.0; a.len() * n];
        for (row, state) in table.chunks_exact_mut(n).zip(a) {
            for ((w, ray), column) in c.weights.iter().zip(&c.rays).zip(columns.chunks_exact(n)) {
                match scales::ray_point(state, ray) {
                    Some(pa) => {
                        for (t, pb) in row.iter_mut().zip(column) {
                            let [g1, g2] = self.truncation.costs(&pa, pb);
                            *t += w * (g1 + g2);
                        }
                    }
                    None => row.iter_mut().for_each(|t| *t += w * full),
                }
            }
        }
        table
    }

    /// E of the soup's current states.
    pub fn energy(&self, soup: &Soup) -> f64 {
        let ground_scale = self.ground.as_ref().map_or(1.0, |g| g.scale(soup));
        let unary: f64 = soup
            .pieces
            .iter()
            .enumerate()
            .map(|(i, p)| self.unary(i, p) + self.ground_cost(i, p, ground_scale))
            .sum();
        unary + self.contact_energy(soup)
    }

    /// Σ E_cont over the touching pairs at the soup's current states.
    fn contact_energy(&self, soup: &Soup) -> f64 {
        (self.contacts.iter())
            .map(|c| self.contact_table(c, &[soup.pieces[c.a]], &[soup.pieces[c.b]])[0])
            .sum()
    }

    /// The terms of E at the soup's current states (their sum is [`Problem::energy`] up to
    /// rounding).
    pub fn energy_terms(&self, soup: &Soup) -> EnergyTerms {
        let ground_scale = self.ground.as_ref().map_or(1.0, |g| g.scale(soup));
        let pieces = soup.pieces.iter().enumerate();
        EnergyTerms {
            proj: pieces.clone().map(|(i, p)| self.unary(i, p)).sum(),
            contacts: self.contact_energy(soup),
            ground: pieces
                .map(|(i, p)| self.ground_cost(i, p, ground_scale))
                .sum(),
        }
    }
}

/// The refinement's energy E term by term.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnergyTerms {
    /// w_proj Σ_i E_proj(θ_i).
    pub proj: f64,
    /// Σ E_cont over touching pairs (both frames).
    pub contacts: f64,
    /// Σ_i E_ground(θ_i).
    pub ground: f64,
}

/// Refines `soup` in place and reports the energies.
pub fn refine(soup: &mut Soup, problem: &Problem) -> RefineReport {
    let params = problem.params;
    let mut energies = vec![problem.energy(soup)];
    let mut lower_bounds = Vec::new();
    let mut rng = Rng::new(params.seed);
    for iteration in 0..params.iterations {
        let shrink = 0.5f64.powi(iteration as i32);
        let particles: Vec<Vec<Piece>> = (0..soup.pieces.len())
            .map(|i| draw_particles(soup, problem, i, shrink, &mut rng))
            .collect();
        let ground_scale = problem.ground.as_ref().map_or(1.0, |g| g.scale(soup));
        let unary: Vec<Vec<f64>> = particles
            .iter()
            .enumerate()
            .map(|(i, ps)| {
                ps.iter()
                    .map(|p| problem.unary(i, p) + problem.ground_cost(i, p, ground_scale))
                    .collect()
            })
            .collect();
        let mut mrf = Mrf::new(unary);
        for c in &problem.contacts {
            let table = problem.contact_table(c, &particles[c.a], &particles[c.b]);
            mrf.add_edge(c.a, c.b, table);
        }
        let current = vec![0; soup.pieces.len()];
        let result = trws(
            &mrf,
            &TrwsOptions {
                iterations: params.trws_passes,
            },
        );
        lower_bounds.push(result.lower_bound);
        let labels = if result.energy < mrf.energy(&current) {
            result.labels
        } else {
            current
        };
        let previous = soup.pieces.clone();
        for (piece, (ps, &l)) in soup.pieces.iter_mut().zip(particles.iter().zip(&labels)) {
            *piece = ps[l];
        }
        // E does not see a global scale: the median λ goes back to 1.
        let log_scales: Vec<f64> = soup.pieces.iter().map(|p| ln(p.lambda)).collect();
        scales::set_scales(soup, &log_scales);
        // The tables held the ground at the iteration's start; where the world's scale moved
        // enough to raise E after all, the iteration is undone.
        let mut energy = problem.energy(soup);
        let before = energies.last().copied().unwrap_or(f64::INFINITY);
        if energy > before {
            soup.pieces = previous;
            energy = before;
        }
        energies.push(energy);
    }
    let tail_pieces = depth_tail_control(soup, problem);
    RefineReport {
        energies,
        lower_bounds,
        tail_pieces,
    }
}

/// Pieces whose depth at the anchor or at a corner of their bounding box lies more than
/// `max_depth_ratio` from the median anchor depth take the state of their touching piece
/// nearest the median (repeated so clusters of such pieces are reached from their rim).
/// Returns how many pieces changed.
fn depth_tail_control(soup: &mut Soup, problem: &Problem) -> usize {
    let limit = ln(problem.params.max_depth_ratio.max(1.0));
    let anchor_depth = |soup: &Soup, i: usize| ln(soup.pieces[i].depth(&problem.extent_rays[i][0]));
    // The extreme log-depth of the piece (anchor and corners), NaN if any is not in front.
    let log_depth = |soup: &Soup, i: usize, centre: f64| {
        problem.extent_rays[i]
            .iter()
            .map(|r| ln(soup.pieces[i].depth(r)))
            .fold(anchor_depth(soup, i), |worst, v| {
                if !v.is_finite() || !worst.is_finite() {
                    f64::NAN
                } else if (v - centre).abs() > (worst - centre).abs() {
                    v
                } else {
                    worst
                }
            })
    };
    let mut logs: Vec<f64> = (0..soup.pieces.len())
        .map(|i| anchor_depth(soup, i))
        .filter(|v| v.is_finite())
        .collect();
    if logs.is_empty() {
        return 0;
    }
    logs.sort_by(f64::total_cmp);
    let centre = logs[logs.len() / 2];
    let outside = |v: f64| !v.is_finite() || (v - centre).abs() > limit;
    let mut changed = vec![false; soup.pieces.len()];
    for _ in 0..soup.pieces.len() {
        let mut moved = false;
        #[allow(clippy::needless_range_loop)] // pieces are read through `soup` while one changes
        for i in 0..soup.pieces.len() {
            if !outside(log_depth(soup, i, centre)) {
                continue;
            }
            let best = problem.neighbours[i]
                .iter()
                .map(|&(k, c)| (k, c, anchor_depth(soup, k)))
                .filter(|&(_, _, v)| !outside(v))
                .min_by(|a, b| (a.2 - centre).abs().total_cmp(&(b.2 - centre).abs()));
            if let Some((k, c, _)) = best {
                let degenerate = soup.pieces[i].degenerate;
                let z = problem.boundary_depth(&soup.pieces[k], c);
                soup.pieces[i] = Piece {
                    degenerate,
                    ..flattened(&soup.pieces[k], z)
                };
                changed[i] = true;
                moved = true;
            }
        }
        if !moved {
            break;
        }
    }
    changed.iter().filter(|&&c| c).count()
}

/// Particles of piece `i`: its current state, its neighbours' states, then perturbations of
/// its log-scale (spread `scale_spread · shrink`) and of its plane (relative spread
/// `plane_spread · shrink`), up to `particles` in all.
fn draw_particles(
    soup: &Soup,
    problem: &Problem,
    i: usize,
    shrink: f64,
    rng: &mut Rng,
) -> Vec<Piece> {
    let params = &problem.params;
    let current = soup.pieces[i];
    let count = params.particles.max(1);
    let mut out = vec![current];
    // A piece without flow of its own also gets each neighbour's motion with a plane facing the
    // camera at the neighbour's depth on their shared boundary: extending a neighbour's tilted
    // plane across a whole superpixel can throw it arbitrarily far.
    let flat = problem.samples[i].is_empty();
    for &(k, c) in &problem.neighbours[i] {
        if out.len() >= count.div_ceil(2).max(1) {
            break;
        }
        let neighbour = soup.pieces[k];
        let mut candidates = vec![neighbour];
        if flat {
            candidates.push(flattened(&neighbour, problem.boundary_depth(&neighbour, c)));
        }
        for mut p in candidates {
            p.degenerate = current.degenerate;
            if p.lambda.is_finite() && !out.iter().any(|q| same_state(q, &p)) {
                out.push(p);
            }
        }
    }
    while out.len() < count {
        let mut p = current;
        p.lambda *= exp(params.scale_spread * shrink * rng.normal());
        if out.len() % 2 == 0 {
            let n = p.m.norm();
            let d = Vector3::new(rng.normal(), rng.normal(), rng.normal());
            p.m += d * (params.plane_spread * shrink * n);
        }
        out.push(p);
    }
    out
}

/// `state`'s motion and scale with a plane facing the camera (normal along z) at depth `z`.
fn flattened(state: &Piece, z: f64) -> Piece {
    Piece {
        m: Vector3::new(0.0, 0.0, state.lambda / z),
        ..*state
    }
}

fn same_state(a: &Piece, b: &Piece) -> bool {
    a.lambda == b.lambda && a.m == b.m && a.r == b.r && a.t_hat == b.t_hat
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A state near the plane z = 5 moving towards the camera; every fourth one's plane faces
    /// away, so it lies behind the camera on every ray.
    fn state(rng: &mut Rng, k: usize) -> Piece {
        let m = Vector3::new(0.05 * rng.normal(), 0.05 * rng.normal(), 0.2);
        Piece {
            r: *nalgebra::Rotation3::new(Vector3::new(0.0, 0.02 * rng.normal(), 0.0)).matrix(),
            t_hat: Vector3::new(0.2 * rng.normal(), 0.0, -1.0).normalize(),
            m: if k % 4 == 3 { -m } else { m },
            lambda: (0.1 * rng.normal()).exp(),
            hypothesis: 0,
            degenerate: None,
        }
    }

    #[test]
    fn contact_tables_match_the_pairwise_sum_of_truncated_gaps() {
        let mut rng = Rng::new(5);
        let rays: Vec<Vector3<f64>> = (0..12)
            .map(|_| Vector3::new(0.3 * rng.normal(), 0.3 * rng.normal(), 1.0))
            .collect();
        let weights: Vec<f64> = (0..12).map(|_| rng.uniform() / 6.0).collect();
        let truncation = TruncatedGaps::new(0.1);
        let problem = Problem {
            samples: vec![Vec::new(); 2],
            extent_rays: Vec::new(),
            contacts: vec![Contact {
                a: 0,
                b: 1,
                rays: rays.clone(),
                weights: weights.clone(),
            }],
            neighbours: Vec::new(),
            focal: 1.0,
            truncation,
            ground: None,
            params: RefineParams::default(),
        };
        let a: Vec<Piece> = (0..9).map(|k| state(&mut rng, k)).collect();
        let b: Vec<Piece> = (0..7).map(|k| state(&mut rng, k + 1)).collect();
        let table = problem.contact_table(&problem.contacts[0], &a, &b);
        let mut inside = 0;
        for (i, sa) in a.iter().enumerate() {
            for (j, sb) in b.iter().enumerate() {
                let reference: f64 = rays
                    .iter()
                    .zip(&weights)
                    .map(|(ray, w)| {
                        match (scales::ray_point(sa, ray), scales::ray_point(sb, ray)) {
                            (Some(pa), Some(pb)) => {
                                let [g1, g2] = truncation.costs(&pa, &pb);
                                inside += usize::from(g1 < 0.1 && g2 < 0.1);
                                w * (g1 + g2)
                            }
                            _ => w * 0.2,
                        }
                    })
                    .sum();
                let got = table[i * b.len() + j];
                assert!(
                    (got - reference).abs() < 1e-12,
                    "{i} {j}: {got} against {reference}"
                );
            }
        }
        assert!(inside > 50, "only {inside} ray pairs inside the truncation");
        // The energy's terms add up to it.
        let soup = Soup {
            pieces: vec![a[0], b[0]],
            hypotheses: Vec::new(),
            noise_px: 0.0,
        };
        let terms = problem.energy_terms(&soup);
        let sum = terms.proj + terms.contacts + terms.ground;
        assert!(terms.contacts > 0.0);
        assert!((sum - problem.energy(&soup)).abs() < 1e-12);
    }
}
