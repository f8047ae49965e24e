//! Procedural textures: colour as a function of material coordinates (a, b) in scene units
//! (metres) on a surface, so a texture sticks to its surface as the surface moves. Every texture
//! carries fine-scale noise so optical flow has something to lock on at every scale.

/// Kinds of procedural pattern.
#[derive(Clone, Copy, Debug)]
pub enum Pattern {
    /// Multi-octave value noise blending the palette.
    Noise,
    /// Running-bond bricks with mortar lines and per-brick colour.
    Bricks,
    /// Parallel stripes at an angle, noisy.
    Stripes,
    /// A colour gradient along `a` with noise on top.
    Gradient,
    /// Checker cells with per-cell colour and noise.
    Checker,
}

/// A procedural texture: a pattern, its cell size in metres, a palette and a seed.
#[derive(Clone, Debug)]
pub struct Texture {
    pub pattern: Pattern,
    /// Characteristic size of the pattern in scene units.
    pub scale: f64,
    /// Colours in linear-ish [0, 1] RGB; patterns blend between them.
    pub palette: [[f64; 3]; 3],
    pub seed: u32,
}

impl Texture {
    pub fn new(pattern: Pattern, scale: f64, palette: [[f64; 3]; 3], seed: u32) -> Self {
        Texture {
            pattern,
            scale,
            palette,
            seed,
        }
    }

    /// Colour in [0, 1] at material coordinates (a, b), times a per-face `tint`.
    pub fn colour(&self, a: f64, b: f64, tint: f64) -> [f64; 3] {
        let (x, y) = (a / self.scale, b / self.scale);
        let seed = self.seed;
        let fine = fbm(a * 9.0, b * 9.0, seed ^ 0x9e37, 3) - 0.5; // detail at ~10 cm
        let [c0, c1, c2] = self.palette;
        let base = match self.pattern {
            Pattern::Noise => {
                let n = fbm(x, y, seed, 5);
                let m = fbm(x * 0.5 + 11.0, y * 0.5, seed ^ 0x51, 3);
                mix(mix(c0, c1, n), c2, smooth(m))
            }
            Pattern::Bricks => {
                let row = y.floor();
                let xs = x * 0.5 + 0.5 * (row.rem_euclid(2.0));
                let (col, fx, fy) = (xs.floor(), xs.fract(), y.fract());
                let mortar = fx < 0.05 || fy < 0.1;
                if mortar {
                    mix(c2, [0.8, 0.8, 0.78], 0.5)
                } else {
                    let h = hash2(col as i64, row as i64, seed);
                    mix(c0, c1, h)
                }
            }
            Pattern::Stripes => {
                let s = (x * 0.8 + y * 0.6 + 0.3 * fbm(x, y, seed, 2)) * std::f64::consts::TAU;
                let t = 0.5 + 0.5 * s.sin();
                mix(mix(c0, c1, t), c2, 0.3 * fbm(x * 2.0, y * 2.0, seed ^ 7, 3))
            }
            Pattern::Gradient => {
                let t = (0.5 + 0.5 * (a * 0.15 + b * 0.05).sin()).clamp(0.0, 1.0);
                mix(mix(c0, c1, t), c2, fbm(x, y, seed, 4) * 0.6)
            }
            Pattern::Checker => {
                let (i, j) = (x.floor() as i64, y.floor() as i64);
                let h = hash2(i, j, seed);
                let c = if (i + j).rem_euclid(2) == 0 { c0 } else { c1 };
                mix(c, c2, 0.5 * h + 0.3 * fbm(x * 3.0, y * 3.0, seed, 2))
            }
        };
        let detail = 1.0 + 0.35 * fine;
        base.map(|c| (c * detail * tint).clamp(0.0, 1.0))
    }
}

fn mix(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    [
        a[0] + (b[0] - a[0]) * t,
        a[1] + (b[1] - a[1]) * t,
        a[2] + (b[2] - a[2]) * t,
    ]
}

fn smooth(t: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// A hash of a lattice point to [0, 1).
fn hash2(i: i64, j: i64, seed: u32) -> f64 {
    let mut h = (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (j as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        ^ (seed as u64).wrapping_mul(0x1656_67B1_9E37_79F9);
    h ^= h >> 33;
    h = h.wrapping_mul(0xFF51_AFD7_ED55_8CCD);
    h ^= h >> 33;
    (h >> 11) as f64 / (1u64 << 53) as f64
}

/// Smoothly interpolated value noise in [0, 1].
fn value_noise(x: f64, y: f64, seed: u32) -> f64 {
    let (i, j) = (x.floor(), y.floor());
    let (fx, fy) = (smooth(x - i), smooth(y - j));
    let (i, j) = (i as i64, j as i64);
    let a = hash2(i, j, seed) + (hash2(i + 1, j, seed) - hash2(i, j, seed)) * fx;
    let b = hash2(i, j + 1, seed) + (hash2(i + 1, j + 1, seed) - hash2(i, j + 1, seed)) * fx;
    a + (b - a) * fy
}

/// Fractal sum of `octaves` value-noise layers, in [0, 1].
fn fbm(x: f64, y: f64, seed: u32, octaves: u32) -> f64 {
    let (mut sum, mut amp, mut norm, mut f) = (0.0, 1.0, 0.0, 1.0);
    for o in 0..octaves {
        sum += amp * value_noise(x * f + o as f64 * 17.0, y * f, seed.wrapping_add(o * 101));
        norm += amp;
        amp *= 0.55;
        f *= 2.03;
    }
    sum / norm
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_pattern_is_in_range_and_varied() {
        let palette = [[0.8, 0.2, 0.1], [0.1, 0.5, 0.9], [0.9, 0.9, 0.2]];
        for pattern in [
            Pattern::Noise,
            Pattern::Bricks,
            Pattern::Stripes,
            Pattern::Gradient,
            Pattern::Checker,
        ] {
            let t = Texture::new(pattern, 0.5, palette, 3);
            let samples: Vec<[f64; 3]> = (0..400)
                .map(|i| t.colour(i as f64 * 0.037, i as f64 * 0.011, 1.0))
                .collect();
            assert!(samples.iter().flatten().all(|c| (0.0..=1.0).contains(c)));
            let mean = samples.iter().map(|c| c[0]).sum::<f64>() / 400.0;
            let var = samples.iter().map(|c| (c[0] - mean).powi(2)).sum::<f64>() / 400.0;
            assert!(var > 1e-3, "{pattern:?} is too flat: variance {var}");
        }
    }
}
