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
//! iteration the median scale is reset to 1 (E ignores the global scale). Then scale
//! expansions move clusters of pieces whose depth is a guess together: every such piece is
//! offered its state or its scale × f at once, TRW-S labels that binary MRF, and a move is kept
//! when it lowers E without raising the scale solve's energy (`expand_scales`; the particles
//! alone cannot move a cluster held by its own inner contacts). At the end, a depth
//! tail control gives pieces placed more than `max_depth_ratio` from the median depth a
//! neighbour's motion and a camera-facing plane at their shared boundary's depth.

use nalgebra::Vector3;
use serde::Serialize;

use super::ground;
use super::init::sample_correspondences;
use super::plane::mean_transfer_px;
use super::scales::{
    self, PointColumns, ScaleEnergy, ScaleInputs, ScaleParams, TruncatedGaps, pair_weight,
    sampled_pairs,
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
    /// Rounds of scale expansions after the particle iterations (module docs; 0 turns
    /// them off).
    pub expansion_rounds: usize,
    /// The expansions' factors, each tried as a shrink f and a growth 1/f, in this order:
    /// halving first (the creature's walker sat at 0.48 of its depth), then the factors around
    /// it. Factors nearer 1 (0.8, 1.25) let parts of the static room slide (0.0086 → 0.0108).
    pub expansion_factors: [f64; 4],
    /// Fewest connected pieces an expansion moves together; smaller groups stay (1–5 pieces of
    /// the street's cars flipped by 2.5× on noise in their truncated contacts: +0.004 there).
    pub expansion_min_group: usize,
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
            expansion_rounds: 1,
            expansion_factors: [0.5, 0.4, 0.6, 0.7],
            expansion_min_group: 8,
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
    /// Scale expansions kept (module docs).
    pub expansions: usize,
    /// Pieces those expansions moved, counted once per expansion.
    pub expanded_pieces: usize,
    /// E after the expansions (the last of `energies` when none was kept).
    pub expansion_energy: f64,
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
    /// The static world's ground plane, if one is in view: at the unit scale of the ego-motion
    /// (depth 1 / (mᵀx̄)), fitted by [`ground::ground_plane`] to the `world` pieces; it lies at
    /// their median scale ([`Problem::ground_scale`]).
    ground: Option<Vector3<f64>>,
    params: RefineParams,
    /// The static world's well-measured pieces ([`scales::world_pieces`]).
    world: Vec<usize>,
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
        let is_world = scales::world_pieces(soup, inputs, scale_params.world_parallax);
        let world: Vec<usize> = (0..is_world.len()).filter(|&i| is_world[i]).collect();
        let ground = (params.ground_weight > 0.0 && scale_params.looks_for_ground())
            .then(|| ground::ground_plane(soup, sp, k, &is_world, scale_params.ground_share))
            .flatten();
        Problem {
            world,
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

    /// The ground's scale in `soup`: the median λ of the world pieces.
    fn ground_scale(&self, soup: &Soup) -> f64 {
        let mut lambdas: Vec<f64> = self.world.iter().map(|&i| soup.pieces[i].lambda).collect();
        lambdas.sort_by(f64::total_cmp);
        lambdas.get(lambdas.len() / 2).copied().unwrap_or(1.0)
    }

    /// The ground's cost of piece `i` in state `piece` with the ground at scale `ground_scale`
    /// ([`Problem::ground_scale`]): `ground_weight` broken contacts where its anchor lies more
    /// than σ under the ground, 0 above the horizon or without a ground.
    fn ground_cost(&self, i: usize, piece: &Piece, ground_scale: f64) -> f64 {
        let Some(ground) = &self.ground else {
            return 0.0;
        };
        let ray = &self.extent_rays[i][0];
        let inv = ground.dot(ray);
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
    /// `c.b`: element `i · b.len() + j` is `E_cont(a[i], b[j])`. The loops run over `b` innermost
    /// on columns of plain numbers ([`PointColumns`]: a state behind a camera on a ray is NaN there
    /// and pays σ in both frames through the comparisons of [`TruncatedGaps::add_costs`]), so
    /// where tanh σ ≤ 0.1 (the default σ = 0.1) they compile to vector instructions without
    /// branches: this table is most of the refinement's time.
    fn contact_table(&self, c: &Contact, a: &[Piece], b: &[Piece]) -> Vec<f64> {
        let full = 2.0 * self.truncation.sigma();
        let columns = PointColumns::new(b, &c.rays);
        let n = b.len();
        let mut table = vec![0.0; a.len() * n];
        for (row, state) in table.chunks_exact_mut(n).zip(a) {
            for (r, (w, ray)) in c.weights.iter().zip(&c.rays).enumerate() {
                match scales::ray_point(state, ray) {
                    Some(pa) => self.truncation.add_costs(*w, &pa, &columns.ray(r), row),
                    None => row.iter_mut().for_each(|t| *t += w * full),
                }
            }
        }
        table
    }

    /// E of the soup's current states.
    pub fn energy(&self, soup: &Soup) -> f64 {
        let ground_scale = self.ground_scale(soup);
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
        let ground_scale = self.ground_scale(soup);
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
pub fn refine(
    soup: &mut Soup,
    problem: &Problem,
    inputs: &ScaleInputs,
    scale_params: &ScaleParams,
) -> RefineReport {
    let params = problem.params;
    let mut energies = vec![problem.energy(soup)];
    let mut lower_bounds = Vec::new();
    let mut rng = Rng::new(params.seed);
    for iteration in 0..params.iterations {
        let shrink = 0.5f64.powi(iteration as i32);
        let particles: Vec<Vec<Piece>> = (0..soup.pieces.len())
            .map(|i| draw_particles(soup, problem, i, shrink, &mut rng))
            .collect();
        let ground_scale = problem.ground_scale(soup);
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
        renormalise(soup);
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
    let (expansions, expanded_pieces) = expand_scales(soup, problem, inputs, scale_params);
    let expansion_energy = problem.energy(soup);
    let tail_pieces = depth_tail_control(soup, problem);
    RefineReport {
        energies,
        lower_bounds,
        expansions,
        expanded_pieces,
        expansion_energy,
        tail_pieces,
    }
}

/// Scale expansions after the particle iterations (ours; not in the paper). The particles move
/// one piece at a time, so a cluster of pieces placed together at a wrong scale (a walker at
/// half its depth, held by its own inner contacts) cannot leave it: any one piece alone would
/// break its contacts with the rest. An expansion offers every piece at once its state or its
/// state with λ multiplied by a factor f (its homography, so E_proj, unchanged: both frames'
/// depths scale together), and TRW-S picks the labelling, as in α-expansion. Each factor of
/// `expansion_factors` is tried as a shrink f and as a growth 1/f, for `expansion_rounds`
/// rounds. Only pieces whose depth is a guess take part ([`guessed_pieces`], decided once,
/// before the first expansion: a piece moved stays movable). A move is kept
/// when
///
/// - it lowers E, counting only the groups of at least `expansion_min_group` connected pieces
///   it moves (smaller ones stay: single pieces are the particles' business, and a few pieces
///   at a depth edge flipping by 2× ride on noise in truncated contacts);
/// - and it does not raise the scale solve's energy at the new scales ([`ScaleEnergy`]: its
///   per-piece contacts plus its segments' contacts, static, rest, figure and ground priors): the
///   refinement's energy does not know the scale solve's priors, and alone took the table's
///   and the road's static world to wrong scales (docs/RESULTS.md, Stop 38).
///
/// Returns how many moves were kept and how many pieces they moved in all.
fn expand_scales(
    soup: &mut Soup,
    problem: &Problem,
    inputs: &ScaleInputs,
    scale_params: &ScaleParams,
) -> (usize, usize) {
    let params = &problem.params;
    let movable = guessed_pieces(soup, problem, inputs, scale_params);
    // Nothing to do without a connected group of guesses large enough to move.
    let mut groups: Vec<usize> = movable.iter().map(|&m| usize::from(m)).collect();
    drop_small_groups(&mut groups, &problem.neighbours, params.expansion_min_group);
    if groups.iter().all(|&g| g == 0) {
        return (0, 0);
    }
    let movable: Vec<bool> = groups.iter().map(|&g| g == 1).collect();
    // The scale energy and its value at the current scales, built at the first move that lowers
    // E (expansions change scales only, so its contacts and segments stay valid).
    let mut scale: Option<(ScaleEnergy, f64)> = None;
    let (mut moves, mut moved) = (0, 0);
    for _ in 0..params.expansion_rounds {
        for &f in &params.expansion_factors {
            for factor in [f, 1.0 / f] {
                let previous = soup.pieces.clone();
                let count = expansion(soup, problem, &movable, factor);
                if count == 0 {
                    continue;
                }
                let (energy, current) = scale.get_or_insert_with(|| {
                    let energy = ScaleEnergy::new(soup, inputs, scale_params);
                    let current = energy.total(&log_scales(&previous));
                    (energy, current)
                });
                let after = energy.total(&log_scales(&soup.pieces));
                if after > *current {
                    soup.pieces = previous;
                    continue;
                }
                *current = after;
                moves += 1;
                moved += count;
            }
        }
    }
    (moves, moved)
}

/// Per piece, whether its depth is a guess that an expansion may move: its depth confidence
/// is below `scales.min_confidence` (no contact pins its scale, or its plane is borrowed) and
/// it is not one of the static world's well-measured pieces still on the ego-motion (their
/// depth is the ego-motion's triangulation at the world's scale). Measured: letting pinned
/// pieces move too took half of the table's static world to half its scale on one seed (0.024
/// → 0.125) and FlyingThings3D's background with two objects to twice (0.32 → 0.42), each at a
/// lower energy than the solution's.
fn guessed_pieces(
    soup: &Soup,
    problem: &Problem,
    inputs: &ScaleInputs,
    scale_params: &ScaleParams,
) -> Vec<bool> {
    let confidence = scales::depth_confidence(soup, inputs, scale_params);
    let mut movable: Vec<bool> = confidence
        .iter()
        .map(|&c| c < scale_params.min_confidence)
        .collect();
    for &i in &problem.world {
        movable[i] &= soup.pieces[i].hypothesis != 0;
    }
    movable
}

/// One expansion by `factor` of the `movable` pieces (see [`expand_scales`]), kept when it
/// lowers E. Returns how many pieces it moved (0 when it was not kept).
fn expansion(soup: &mut Soup, problem: &Problem, movable: &[bool], factor: f64) -> usize {
    // The MRF holds the movable pieces only; a contact with a piece that keeps its state adds
    // its cost to the movable side's unary.
    let nodes: Vec<usize> = (0..movable.len()).filter(|&i| movable[i]).collect();
    let mut node_of = vec![usize::MAX; movable.len()];
    for (n, &i) in nodes.iter().enumerate() {
        node_of[i] = n;
    }
    let states = |i: usize| -> Vec<Piece> {
        let p = soup.pieces[i];
        if movable[i] {
            vec![
                p,
                Piece {
                    lambda: p.lambda * factor,
                    ..p
                },
            ]
        } else {
            vec![p]
        }
    };
    let ground_scale = problem.ground_scale(soup);
    let mut unary: Vec<Vec<f64>> = nodes
        .iter()
        .map(|&i| {
            states(i)
                .iter()
                .map(|p| problem.ground_cost(i, p, ground_scale))
                .collect()
        })
        .collect();
    let mut edges = Vec::new();
    for c in &problem.contacts {
        match (movable[c.a], movable[c.b]) {
            (true, true) => edges.push((c, problem.contact_table(c, &states(c.a), &states(c.b)))),
            (true, false) | (false, true) => {
                // The fixed side has one state, so the table runs over the movable side's.
                let side = if movable[c.a] { c.a } else { c.b };
                let table = problem.contact_table(c, &states(c.a), &states(c.b));
                let u = &mut unary[node_of[side]];
                u.iter_mut().zip(&table).for_each(|(u, t)| *u += t);
            }
            (false, false) => {}
        }
    }
    let mut mrf = Mrf::new(unary);
    for (c, table) in edges {
        mrf.add_edge(node_of[c.a], node_of[c.b], table);
    }
    let options = TrwsOptions {
        iterations: problem.params.trws_passes,
    };
    let node_labels = trws(&mrf, &options).labels;
    let mut labels = vec![0; movable.len()];
    for (&i, &l) in nodes.iter().zip(&node_labels) {
        labels[i] = l;
    }
    drop_small_groups(
        &mut labels,
        &problem.neighbours,
        problem.params.expansion_min_group,
    );
    let kept: Vec<usize> = nodes.iter().map(|&i| labels[i]).collect();
    let count = kept.iter().filter(|&&l| l == 1).count();
    if count == 0 || mrf.energy(&kept) >= mrf.energy(&vec![0; kept.len()]) {
        return 0;
    }
    let before = problem.energy(soup);
    let previous = soup.pieces.clone();
    for (piece, &l) in soup.pieces.iter_mut().zip(&labels) {
        if l == 1 {
            piece.lambda *= factor;
        }
    }
    renormalise(soup);
    if problem.energy(soup) >= before {
        soup.pieces = previous;
        return 0;
    }
    count
}

/// ln λ of each of `pieces`.
fn log_scales(pieces: &[Piece]) -> Vec<f64> {
    pieces.iter().map(|p| ln(p.lambda)).collect()
}

/// Resets the median λ of `soup` to 1 (the refinement's energy does not see a global scale).
fn renormalise(soup: &mut Soup) {
    scales::set_scales(soup, &log_scales(&soup.pieces));
}

/// Sets to 0 the labels of every connected group (through `neighbours`) of pieces labelled 1
/// that has fewer than `min_group` pieces.
fn drop_small_groups(labels: &mut [usize], neighbours: &[Vec<(usize, usize)>], min_group: usize) {
    let mut seen = vec![false; labels.len()];
    for start in 0..labels.len() {
        if seen[start] || labels[start] != 1 {
            continue;
        }
        seen[start] = true;
        let mut stack = vec![start];
        let mut group = Vec::new();
        while let Some(i) = stack.pop() {
            group.push(i);
            for &(k, _) in &neighbours[i] {
                if !seen[k] && labels[k] == 1 {
                    seen[k] = true;
                    stack.push(k);
                }
            }
        }
        if group.len() < min_group {
            group.iter().for_each(|&i| labels[i] = 0);
        }
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
            world: Vec::new(),
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
            ego_rival: None,
            rugged_to_ego: 0,
        };
        let terms = problem.energy_terms(&soup);
        let sum = terms.proj + terms.contacts + terms.ground;
        assert!(terms.contacts > 0.0);
        assert!((sum - problem.energy(&soup)).abs() < 1e-12);
    }

    #[test]
    fn expansions_leave_groups_smaller_than_the_minimum_where_they_are() {
        // A chain 0-1-2-3-4 and a pair 5-6; pieces 0, 1, 2, 5 and 6 are labelled to move.
        let mut neighbours = vec![Vec::new(); 7];
        for (c, (a, b)) in [(0, 1), (1, 2), (2, 3), (3, 4), (5, 6)]
            .into_iter()
            .enumerate()
        {
            neighbours[a].push((b, c));
            neighbours[b].push((a, c));
        }
        let moved = [1, 1, 1, 0, 0, 1, 1];
        let mut labels = moved.to_vec();
        drop_small_groups(&mut labels, &neighbours, 3);
        assert_eq!(labels, [1, 1, 1, 0, 0, 0, 0]);
        let mut labels = moved.to_vec();
        drop_small_groups(&mut labels, &neighbours, 4);
        assert_eq!(labels, [0; 7]);
        let mut labels = moved.to_vec();
        drop_small_groups(&mut labels, &neighbours, 1);
        assert_eq!(labels, moved);
    }

    /// Ten pieces in a row, each touching the next through three rays: planes facing the
    /// camera at unit-scale depth 5, all moving by one translation; pieces 5–9 at twice the
    /// scale of 0–4 (a cluster placed together at a wrong scale).
    fn row_with_a_far_cluster() -> (Soup, Problem) {
        let piece = |lambda| Piece {
            r: nalgebra::Matrix3::identity(),
            t_hat: Vector3::new(1.0, 0.0, 0.0),
            m: Vector3::new(0.0, 0.0, 0.2),
            lambda,
            hypothesis: 1,
            degenerate: None,
        };
        let pieces: Vec<Piece> = (0..10)
            .map(|i| piece(if i < 5 { 1.0 } else { 2.0 }))
            .collect();
        let mut neighbours = vec![Vec::new(); 10];
        let mut contacts = Vec::new();
        for a in 0..9 {
            let x = -0.5 + 0.1 * a as f64;
            let rays = (0..3)
                .map(|k| Vector3::new(x, 0.1 * k as f64, 1.0))
                .collect();
            neighbours[a].push((a + 1, contacts.len()));
            neighbours[a + 1].push((a, contacts.len()));
            contacts.push(Contact {
                a,
                b: a + 1,
                rays,
                weights: vec![1.0 / 3.0; 3],
            });
        }
        let problem = Problem {
            samples: vec![Vec::new(); 10],
            extent_rays: Vec::new(),
            contacts,
            neighbours,
            focal: 1.0,
            truncation: TruncatedGaps::new(0.1),
            ground: None,
            params: RefineParams::default(),
            world: Vec::new(),
        };
        let soup = Soup {
            pieces,
            hypotheses: Vec::new(),
            noise_px: 0.1,
            ego_rival: None,
            rugged_to_ego: 0,
        };
        (soup, problem)
    }

    #[test]
    fn an_expansion_moves_a_cluster_of_guesses_back_to_the_scale_its_contacts_say() {
        let (mut soup, mut problem) = row_with_a_far_cluster();
        problem.params.expansion_min_group = 5;
        let before = problem.energy(&soup);
        let movable = vec![true; 10];
        // Doubling the near half (E does not see the global scale) closes the gap.
        let moved = expansion(&mut soup, &problem, &movable, 2.0);
        assert_eq!(moved, 5, "one side of the row moves as a whole");
        let after = problem.energy(&soup);
        assert!(after < before - 0.1, "E {before} -> {after}");
        let ratio = soup.pieces[9].lambda / soup.pieces[0].lambda;
        assert!(
            (ratio - 1.0).abs() < 1e-9,
            "scale ratio across the row {ratio}"
        );
        // Once the row is one surface no expansion lowers E.
        for factor in [0.5, 2.0, 0.7] {
            assert_eq!(expansion(&mut soup, &problem, &movable, factor), 0);
        }
    }

    #[test]
    fn an_expansion_leaves_pinned_pieces_and_small_groups_alone() {
        let (soup, mut problem) = row_with_a_far_cluster();
        // Only the far cluster's pieces are guesses, but a group of 5 is below the minimum.
        problem.params.expansion_min_group = 6;
        let far: Vec<bool> = (0..10).map(|i| i >= 5).collect();
        let mut moved = soup.clone();
        assert_eq!(expansion(&mut moved, &problem, &far, 0.5), 0);
        assert_eq!(moved.pieces, soup.pieces);
        // Nothing may move: nothing does.
        problem.params.expansion_min_group = 1;
        let mut pinned = soup.clone();
        assert_eq!(expansion(&mut pinned, &problem, &[false; 10], 0.5), 0);
        assert_eq!(pinned.pieces, soup.pieces);
        // With the near half pinned, the far cluster itself comes back.
        let mut free = soup.clone();
        assert_eq!(expansion(&mut free, &problem, &far, 0.5), 5);
        let ratio = free.pieces[9].lambda / free.pieces[0].lambda;
        assert!(
            (ratio - 1.0).abs() < 1e-9,
            "scale ratio across the row {ratio}"
        );
    }
}
