//! Dense Inverse Search (Kroeger, Timofte, Dai, Van Gool, "Fast Optical Flow using Dense Inverse
//! Search", ECCV 2016), laid out as OpenCV's `DISOpticalFlow` does it.
//!
//! Coarse to fine over a grey pyramid ([`super::pyramid`]); on each level:
//! 1. a grid of 8 × 8 patches of frame 1 (every `patch_stride` pixels) each starts from the
//!    coarser level's flow at its centre;
//! 2. two sweeps over the grid (forward raster order, then backward) let each patch adopt a
//!    neighbour's displacement when that one matches better (spatial propagation), then refine it
//!    by inverse-compositional Gauss–Newton on mean-normalised patches (the template's gradient
//!    and Hessian are computed once per patch; each iteration only resamples frame 2);
//! 3. the patches are blended into a dense field, each pixel averaging the displacements of the
//!    patches covering it with weight 1 / max(1, |I₂(x + d) − I₁(x)|) (grey levels);
//! 4. variational refinement ([`super::variational`]) polishes the dense field.
//!
//! The finest level computed is `finest_level`; the caller upsamples from there. Flow at a level
//! is in pixels of that level; pixel centres at integers, u right, v down.

use super::lanes::F4;
use super::pyramid::{Level, upsample};
use super::variational::{VariationalParams, refine};
use crate::error::{Error, Result};
use crate::numeric::log2;

/// Speed/accuracy trade-offs, named as OpenCV's DIS presets.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Preset {
    /// Stops two levels above full resolution with a sparse patch grid.
    Fast,
    /// Stops one level above full resolution (OpenCV's default).
    Medium,
    /// Runs to full resolution with medium's patch grid and 3 fixed-point iterations of the
    /// variational refinement instead of 5. On the synthetic street, crowd, creature and road
    /// its error on the vectors that pass the forward–backward check is within 0.02 px of
    /// high's (0.086–0.160 px against 0.081–0.142; medium's 0.166–0.236) in two thirds of
    /// high's time (675 ms against 1045 ms, `cargo bench --bench flow`; medium 205 ms), and the
    /// depth from it is as accurate as from high's (docs/RESULTS.md, stop 58).
    Fine,
    /// Runs to full resolution with a dense patch grid. The default: the soup's planes need
    /// sharp motion boundaries, and medium's half-resolution flow smears a mover's motion over
    /// the 5–10 px of background beside it (on the synthetic crowd, 27 % of the vectors that
    /// pass the forward–backward check 2–5 px from a motion boundary are more than 1 px off,
    /// against 11 % with high), which halves the depth error on most scenes (docs/RESULTS.md).
    #[default]
    High,
}

impl Preset {
    /// Every preset, fastest first.
    pub const ALL: [Preset; 4] = [Preset::Fast, Preset::Medium, Preset::Fine, Preset::High];

    /// Time of the flow both ways relative to `fast` (native, 1024 × 436: 49, 174 and 878 ms;
    /// fine's 675 ms beside medium's 205 ms, stop 58; docs/RESULTS.md, Speed): how the progress
    /// of a run shares out passes of several presets.
    pub fn relative_cost(self) -> f32 {
        match self {
            Preset::Fast => 1.0,
            Preset::Medium => 3.5,
            Preset::Fine => 11.0,
            Preset::High => 18.0,
        }
    }

    /// The preset a reconstruction asks for when this one's flow does not serve it (too little
    /// of it trusted, the camera's motion ambiguous, too few scales pinned, no ground: see
    /// `pipeline::reconstruct`): fast → medium → high, and fine → high. Fine is not on medium's
    /// way: a pass of medium's wanting finer flow is made again from high's, as before fine
    /// existed, so adding it changed no result. (Through fine, the crowd with the page's
    /// settings and a focal length 25 % off took three passes instead of two: fine's pass
    /// pinned 61 %, and high's came all the same, to the same depth, MRE 0.118.)
    pub fn finer(self) -> Option<Preset> {
        match self {
            Preset::Fast => Some(Preset::Medium),
            Preset::Medium | Preset::Fine => Some(Preset::High),
            Preset::High => None,
        }
    }

    /// The name used on the command line: `fast`, `medium`, `fine` or `high`.
    pub fn name(self) -> &'static str {
        match self {
            Preset::Fast => "fast",
            Preset::Medium => "medium",
            Preset::Fine => "fine",
            Preset::High => "high",
        }
    }

    /// The preset called `name`.
    pub fn from_name(name: &str) -> Result<Self> {
        Preset::ALL
            .into_iter()
            .find(|p| p.name() == name)
            .ok_or_else(|| {
                Error::InvalidParameter(format!(
                    "unknown flow preset {name:?}; choose fast, medium, fine or high"
                ))
            })
    }
}

/// Side of the square patches in pixels of each level: 8, as in every preset of OpenCV and of
/// the DIS paper. Fixed so the patch loops work on `[f32; 8]` rows the compiler vectorises.
pub const PATCH: usize = 8;

/// Parameters of DIS.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DisParams {
    /// Distance between neighbouring patch origins, in pixels.
    pub patch_stride: usize,
    /// Finest pyramid level computed (0 = full resolution); the result is upsampled from there.
    pub finest_level: usize,
    /// Gauss–Newton iterations per patch and level, shared by the two propagation sweeps.
    pub iterations: usize,
    /// Share of each Gauss–Newton step taken, in (0, 1]. Full steps jump between the basins of
    /// repetitive texture; shorter ones stay in the basin the start lies in. (OpenCV's
    /// implementation takes 1/8 of the step, a side effect of its unnormalised Sobel
    /// gradients; 0.2–0.3 measured best here.)
    pub step_scale: f32,
    /// Variational refinement run on every level.
    pub variational: VariationalParams,
}

impl DisParams {
    /// The parameters of `preset`.
    pub fn preset(preset: Preset) -> Self {
        // Fewer iterations need longer steps to travel as far. The last number is the
        // variational refinement's fixed-point iterations (VariationalParams::iterations).
        let (patch_stride, finest_level, iterations, step_scale, fixed_point) = match preset {
            Preset::Fast => (4, 2, 16, 0.3, 5),
            Preset::Medium => (3, 1, 25, 0.25, 5),
            // Medium's grid at full resolution, where each fixed-point iteration costs most.
            Preset::Fine => (3, 0, 25, 0.25, 3),
            Preset::High => (2, 0, 32, 0.2, 5),
        };
        DisParams {
            patch_stride,
            finest_level,
            iterations,
            step_scale,
            variational: VariationalParams {
                iterations: fixed_point,
                ..VariationalParams::default()
            },
        }
    }

    /// Fails with [`Error::InvalidParameter`] for values the algorithm cannot run with.
    pub fn validate(&self) -> Result<()> {
        let bad = |what: String| Err(Error::InvalidParameter(what));
        if self.patch_stride == 0 || self.patch_stride > PATCH {
            return bad(format!(
                "patch stride {} must be between 1 and the patch size {PATCH}",
                self.patch_stride
            ));
        }
        if !(self.step_scale > 0.0 && self.step_scale <= 1.0) {
            return bad(format!("step scale {} is outside (0, 1]", self.step_scale));
        }
        if self.finest_level > 8 {
            return bad(format!("finest level {} is above 8", self.finest_level));
        }
        self.variational.validate()
    }
}

impl Default for DisParams {
    fn default() -> Self {
        DisParams::preset(Preset::default())
    }
}

/// The pyramid levels `(finest, coarsest)` DIS runs on for a `width × height` image: the finest
/// is `params.finest_level`, lowered while that level would be smaller than a patch; the coarsest
/// is as OpenCV chooses it: about log₂(long side / 4 patches), and never so coarse that the short
/// side holds less than one patch. `None` when even level 0 is smaller than a patch.
pub fn levels(width: usize, height: usize, params: &DisParams) -> Option<(usize, usize)> {
    let ps = PATCH;
    if width.min(height) < ps {
        return None;
    }
    let mut finest = params.finest_level;
    while finest > 0 && (width >> finest).min(height >> finest) < ps {
        finest -= 1;
    }
    let long = width.max(height) as f64 / (4.0 * ps as f64);
    let by_long = if long > 1.0 {
        log2(long).round() as usize
    } else {
        0
    };
    let by_short = log2((width.min(height) / ps) as f64).floor() as usize;
    Some((finest, by_long.min(by_short).max(finest)))
}

/// Flow from the image of pyramid `from` to that of `to` (levels `finest..` of both, as built by
/// [`super::pyramid::build`]) at the resolution of their first level, as `(u, v)` row-major.
/// `progress` gets the share of the work done, in [0, 1].
pub fn dis_flow(
    from: &[Level],
    to: &[Level],
    params: &DisParams,
    progress: &mut dyn FnMut(f32),
) -> (Vec<f32>, Vec<f32>) {
    let work: f32 = from.iter().map(|l| (l.width * l.height) as f32).sum();
    let mut done = 0.0;
    let mut flow: Option<(Vec<f32>, Vec<f32>, usize, usize)> = None;
    for (a, b) in from.iter().zip(to).rev() {
        let (w, h) = (a.width, a.height);
        let (u0, v0) = match flow.take() {
            Some((u, v, cw, ch)) => (
                upsample(&u, cw, ch, w, h, 2.0),
                upsample(&v, cw, ch, w, h, 2.0),
            ),
            None => (vec![0.0; w * h], vec![0.0; w * h]),
        };
        // The search (its patches, gradients and padded frame 2) and the initial field are
        // dropped before the refinement, whose arrays are the largest of the level.
        let (u, v) = {
            let search = PatchSearch::new(a, b, params);
            let sparse = search.run(&u0, &v0, params.iterations);
            search.densify(&sparse)
        };
        drop((u0, v0));
        let (u, v) = refine(a, b, u, v, &params.variational);
        flow = Some((u, v, w, h));
        done += (w * h) as f32;
        progress(done / work);
    }
    match flow {
        Some((u, v, _, _)) => (u, v),
        None => (Vec::new(), Vec::new()),
    }
}

/// Frame 2 of a level with a replicated border, so a patch displaced anywhere (its origin
/// clamped to at most [`PATCH`] − 1 pixels outside the image) samples without coordinate checks.
struct PaddedImage {
    data: Vec<f32>,
    /// Row length of `data`: width + 2·[`PADDING`].
    stride: usize,
    width: usize,
    height: usize,
}

/// Border added on each side of [`PaddedImage`]: a patch plus the bilinear neighbour.
const PADDING: usize = PATCH + 1;

impl PaddedImage {
    fn new(level: &Level) -> Self {
        let (w, h) = (level.width, level.height);
        let stride = w + 2 * PADDING;
        let mut data = Vec::with_capacity(stride * (h + 2 * PADDING));
        for py in 0..h + 2 * PADDING {
            let row = &level.pixels[py.saturating_sub(PADDING).min(h - 1) * w..][..w];
            data.extend(std::iter::repeat_n(row[0], PADDING));
            data.extend_from_slice(row);
            data.extend(std::iter::repeat_n(row[w - 1], PADDING));
        }
        PaddedImage {
            data,
            stride,
            width: w,
            height: h,
        }
    }

    /// The rows a patch with origin (x, y) displaced by `d` reads and its bilinear weights.
    #[inline]
    fn window(&self, x: usize, y: usize, d: [f32; 2]) -> Window<'_> {
        let lo = 1.0 - PATCH as f32;
        let ox = (x as f32 + d[0]).clamp(lo, (self.width - 1) as f32);
        let oy = (y as f32 + d[1]).clamp(lo, (self.height - 1) as f32);
        // Shifted into the padding the coordinates are positive, so truncation is the floor.
        let (px, py) = (ox + PADDING as f32, oy + PADDING as f32);
        let (ix, iy) = (px as usize, py as usize);
        let (ax, ay) = (px - ix as f32, py - iy as f32);
        Window {
            image: self,
            start: iy * self.stride + ix,
            weights: [
                (1.0 - ax) * (1.0 - ay),
                ax * (1.0 - ay),
                (1.0 - ax) * ay,
                ax * ay,
            ],
        }
    }
}

/// Where a displaced patch reads frame 2: its top-left sample in [`PaddedImage::data`] and the
/// bilinear weights `[top-left, top-right, bottom-left, bottom-right]`, the same for every pixel.
struct Window<'a> {
    image: &'a PaddedImage,
    start: usize,
    weights: [f32; 4],
}

impl Window<'_> {
    /// Columns `c..c + 4` of row `r` of the patch, sampled from frame 2.
    #[inline(always)]
    fn sample(&self, r: usize, c: usize) -> F4 {
        let stride = self.image.stride;
        let top = &self.image.data[self.start + r * stride + c..][..5];
        let bottom = &self.image.data[self.start + (r + 1) * stride + c..][..5];
        let [w00, w01, w10, w11] = self.weights.map(F4::splat);
        w00 * F4::load(top)
            + w01 * F4::load(&top[1..])
            + w10 * F4::load(bottom)
            + w11 * F4::load(&bottom[1..])
    }
}

/// Row `r` of the 8 × 8 patch with origin (x, y) of a flat image of width `w`.
#[inline]
fn patch_row(image: &[f32], w: usize, x: usize, y: usize, r: usize) -> &[f32] {
    let at = (y + r) * w + x;
    &image[at..at + PATCH]
}

/// One level's patch grid with everything about frame 1 that Gauss–Newton reuses.
struct PatchSearch<'a> {
    from: &'a Level,
    /// Frame 1's gradients on this level ([`Level::gradients`]).
    gx: Vec<f32>,
    gy: Vec<f32>,
    to: PaddedImage,
    /// Share of each Gauss–Newton step taken ([`DisParams::step_scale`]).
    step_scale: f32,
    /// Patches per grid row.
    columns: usize,
    /// The patches, row by row.
    patches: Vec<Patch>,
}

/// A patch's mean-normalised SSD and Gauss–Newton gradient (x, y) at one displacement.
type Residual = (f32, f32, f32);

/// One patch of frame 1 and what Gauss–Newton reuses about it.
struct Patch {
    /// Top-left pixel.
    x: usize,
    y: usize,
    /// Inverse of the mean-normalised Gauss–Newton Hessian, `[a, b, c]` of [[a, b], [b, c]].
    inv_hessian: [f32; 3],
    /// Sums of the template's x and y gradients (for mean normalisation).
    grad_sum: [f32; 2],
}

/// Regularisation added to the diagonal of each patch's Hessian, per pixel (grey levels² per
/// pixel²): steps along an edge or in a flat patch stay small instead of exploding.
const HESSIAN_FLOOR: f32 = 0.1;

/// A Gauss–Newton step shorter than this (pixels) ends a patch's iterations.
const CONVERGED_STEP: f32 = 0.03;

/// Pixels in a patch, as a float.
const PIXELS: f32 = (PATCH * PATCH) as f32;

impl<'a> PatchSearch<'a> {
    fn new(from: &'a Level, to: &Level, params: &DisParams) -> Self {
        let xs = origins(from.width, params.patch_stride);
        let ys = origins(from.height, params.patch_stride);
        let (gx, gy) = from.gradients();
        let mut patches = Vec::with_capacity(xs.len() * ys.len());
        for &y in &ys {
            for &x in &xs {
                let (mut sx, mut sy, mut sxx, mut sxy, mut syy) = (0.0f32, 0.0, 0.0, 0.0, 0.0);
                for r in 0..PATCH {
                    let gx = patch_row(&gx, from.width, x, y, r);
                    let gy = patch_row(&gy, from.width, x, y, r);
                    for (&gx, &gy) in gx.iter().zip(gy) {
                        sx += gx;
                        sy += gy;
                        sxx += gx * gx;
                        sxy += gx * gy;
                        syy += gy * gy;
                    }
                }
                // Hessian of the mean-normalised residual: the gradients minus their mean.
                let a = sxx - sx * sx / PIXELS + HESSIAN_FLOOR * PIXELS;
                let b = sxy - sx * sy / PIXELS;
                let c = syy - sy * sy / PIXELS + HESSIAN_FLOOR * PIXELS;
                let det = a * c - b * b;
                patches.push(Patch {
                    x,
                    y,
                    inv_hessian: [c / det, -b / det, a / det],
                    grad_sum: [sx, sy],
                });
            }
        }
        PatchSearch {
            from,
            gx,
            gy,
            to: PaddedImage::new(to),
            step_scale: params.step_scale,
            columns: xs.len(),
            patches,
        }
    }

    /// Patch displacements: each patch starts from the dense initial field (u0, v0) at its
    /// centre, then two propagation sweeps with Gauss–Newton refinement.
    fn run(&self, u0: &[f32], v0: &[f32], iterations: usize) -> Vec<[f32; 2]> {
        let (nx, ny) = (self.columns, self.patches.len() / self.columns);
        let (w, h) = (self.from.width, self.from.height);
        let centre = (PATCH as f32 - 1.0) / 2.0;
        let mut flow: Vec<[f32; 2]> = self
            .patches
            .iter()
            .map(|p| {
                let (cx, cy) = (p.x as f32 + centre, p.y as f32 + centre);
                [
                    super::pyramid::sample_clamped(u0, w, h, cx, cy),
                    super::pyramid::sample_clamped(v0, w, h, cx, cy),
                ]
            })
            .collect();
        let first = iterations - iterations / 2;
        // Forward sweep: candidates from the left and upper neighbours.
        for j in 0..ny {
            for i in 0..nx {
                let k = j * nx + i;
                let left = (i > 0).then(|| flow[k - 1]);
                let up = (j > 0).then(|| flow[k - nx]);
                flow[k] = self.improve(k, flow[k], [left, up], first);
            }
        }
        // Backward sweep: candidates from the right and lower neighbours.
        for j in (0..ny).rev() {
            for i in (0..nx).rev() {
                let k = j * nx + i;
                let right = (i + 1 < nx).then(|| flow[k + 1]);
                let down = (j + 1 < ny).then(|| flow[k + nx]);
                flow[k] = self.improve(k, flow[k], [right, down], iterations / 2);
            }
        }
        flow
    }

    /// Patch `k`'s best start among its current displacement and the neighbours' (lowest
    /// mean-normalised SSD), refined by up to `iterations` Gauss–Newton steps. A refinement that
    /// wanders more than a patch side from its start is dropped, as in OpenCV.
    fn improve(
        &self,
        k: usize,
        current: [f32; 2],
        candidates: [Option<[f32; 2]>; 2],
        iterations: usize,
    ) -> [f32; 2] {
        let mut start = current;
        // The residual at `start`, once evaluated: Gauss–Newton reuses it as its first step.
        let mut at_start: Option<Residual> = None;
        for candidate in candidates.into_iter().flatten() {
            if candidate == start {
                continue;
            }
            let current = *at_start.get_or_insert_with(|| self.residual(k, start));
            let other = self.residual(k, candidate);
            if other.0 < current.0 {
                start = candidate;
                at_start = Some(other);
            }
        }
        let refined = self.descend(k, start, at_start, iterations);
        let (mx, my) = (refined[0] - start[0], refined[1] - start[1]);
        if mx * mx + my * my <= (PATCH * PATCH) as f32 {
            refined
        } else {
            start
        }
    }

    /// Inverse-compositional Gauss–Newton from `start` (whose residual may be known already):
    /// each step, scaled by `step_scale`, solves with the patch's fixed Hessian; stops when a step
    /// is tiny, or when the SSD stops falling (then returns the best point seen).
    fn descend(
        &self,
        k: usize,
        start: [f32; 2],
        mut known: Option<Residual>,
        iterations: usize,
    ) -> [f32; 2] {
        let [a, b, c] = self.patches[k].inv_hessian;
        let mut d = start;
        let mut best = (f32::INFINITY, start);
        for _ in 0..iterations {
            let (ssd, gx, gy) = known.take().unwrap_or_else(|| self.residual(k, d));
            if ssd >= best.0 {
                return best.1;
            }
            best = (ssd, d);
            let (sx, sy) = (
                self.step_scale * (a * gx + b * gy),
                self.step_scale * (b * gx + c * gy),
            );
            d = [d[0] - sx, d[1] - sy];
            if sx * sx + sy * sy < CONVERGED_STEP * CONVERGED_STEP {
                break;
            }
        }
        d
    }

    /// Mean-normalised SSD between patch `k` of frame 1 and frame 2 displaced by `d`, and the
    /// Gauss–Newton gradient Σ (g − ḡ)·r of the template gradients g against the residual r.
    fn residual(&self, k: usize, d: [f32; 2]) -> Residual {
        let patch = &self.patches[k];
        let (x0, y0) = (patch.x, patch.y);
        let window = self.to.window(x0, y0, d);
        let w = self.from.width;
        // Partial sums in four lanes (columns c and c + 4 share lane c).
        let (mut sum, mut sq, mut bx, mut by) =
            (F4::default(), F4::default(), F4::default(), F4::default());
        for r in 0..PATCH {
            let template = patch_row(&self.from.pixels, w, x0, y0, r);
            let gx = patch_row(&self.gx, w, x0, y0, r);
            let gy = patch_row(&self.gy, w, x0, y0, r);
            for c in [0, 4] {
                let residual = window.sample(r, c) - F4::load(&template[c..]);
                sum += residual;
                sq += residual * residual;
                bx += F4::load(&gx[c..]) * residual;
                by += F4::load(&gy[c..]) * residual;
            }
        }
        let [s, q, bx, by] = [sum, sq, bx, by].map(F4::sum);
        let [gsx, gsy] = patch.grad_sum;
        let ssd = (q - s * s / PIXELS).max(0.0);
        (ssd, bx - s * gsx / PIXELS, by - s * gsy / PIXELS)
    }

    /// The dense field: every pixel averages the displacements of the patches covering it, each
    /// weighted by 1 / max(1, |I₂(x + d) − I₁(x)|).
    fn densify(&self, flow: &[[f32; 2]]) -> (Vec<f32>, Vec<f32>) {
        let (w, h) = (self.from.width, self.from.height);
        let mut su = vec![0.0f32; w * h];
        let mut sv = vec![0.0f32; w * h];
        let mut sw = vec![0.0f32; w * h];
        for (patch, &d) in self.patches.iter().zip(flow) {
            let (x0, y0) = (patch.x, patch.y);
            let window = self.to.window(x0, y0, d);
            for r in 0..PATCH {
                let template = patch_row(&self.from.pixels, w, x0, y0, r);
                let at = (y0 + r) * w + x0;
                for c in [0, 4] {
                    let sample = window.sample(r, c).0;
                    let rows = (
                        &mut su[at + c..at + c + 4],
                        &mut sv[at + c..at + c + 4],
                        &mut sw[at + c..at + c + 4],
                    );
                    for (i, ((u, v), s)) in rows.0.iter_mut().zip(rows.1).zip(rows.2).enumerate() {
                        let weight = 1.0 / (sample[i] - template[c + i]).abs().max(1.0);
                        *u += weight * d[0];
                        *v += weight * d[1];
                        *s += weight;
                    }
                }
            }
        }
        // Every pixel is covered: the grid always includes the last origin on each axis.
        for ((u, v), s) in su.iter_mut().zip(sv.iter_mut()).zip(&sw) {
            *u /= s;
            *v /= s;
        }
        (su, sv)
    }
}

/// Patch origins along an axis of `len` ≥ [`PATCH`] pixels: every `stride`, plus the last one
/// that fits, so every pixel is covered.
fn origins(len: usize, stride: usize) -> Vec<usize> {
    let last = len - PATCH;
    let mut out: Vec<usize> = (0..=last).step_by(stride).collect();
    if out.last() != Some(&last) {
        out.push(last);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn origins_cover_the_axis() {
        assert_eq!(origins(20, 3), vec![0, 3, 6, 9, 12]);
        assert_eq!(origins(21, 3), vec![0, 3, 6, 9, 12, 13]);
        assert_eq!(origins(8, 3), vec![0]);
    }

    #[test]
    fn levels_follow_opencv_and_shrink_for_small_images() {
        let p = DisParams::preset(Preset::Medium);
        assert_eq!(levels(1024, 436, &p), Some((1, 5)));
        assert_eq!(levels(741, 500, &p), Some((1, 5)));
        assert_eq!(levels(12, 12, &p), Some((0, 0)));
        assert_eq!(levels(7, 100, &p), None);
        let fast = DisParams::preset(Preset::Fast);
        assert_eq!(levels(20, 40, &fast), Some((1, 1)));
    }

    #[test]
    fn finer_flow_goes_fast_medium_high_and_from_fine_to_high() {
        let chain: Vec<Preset> = std::iter::successors(Some(Preset::Fast), |p| p.finer()).collect();
        assert_eq!(chain, [Preset::Fast, Preset::Medium, Preset::High]);
        assert_eq!(Preset::Fine.finer(), Some(Preset::High));
        // Fastest first, and fine runs medium's grid to full resolution.
        assert!(
            Preset::ALL
                .windows(2)
                .all(|p| p[0].relative_cost() < p[1].relative_cost())
        );
        let fine = DisParams::preset(Preset::Fine);
        assert_eq!(levels(1024, 436, &fine), Some((0, 5)));
        assert_eq!(
            fine.patch_stride,
            DisParams::preset(Preset::Medium).patch_stride
        );
    }

    #[test]
    fn presets_parse_and_validate() {
        for preset in Preset::ALL {
            assert_eq!(Preset::from_name(preset.name()).unwrap(), preset);
            DisParams::preset(preset).validate().unwrap();
        }
        assert!(Preset::from_name("slow").is_err());
        let zero_stride = DisParams {
            patch_stride: 0,
            ..Default::default()
        };
        assert!(zero_stride.validate().is_err());
        let long_step = DisParams {
            step_scale: 1.5,
            ..Default::default()
        };
        assert!(long_step.validate().is_err());
    }
}
