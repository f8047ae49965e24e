//! The minimal five-point essential matrix (Stewénius, Engels, Nistér: "Recent developments on
//! direct relative orientation", 2006), on normalised coordinates (x̄'ᵀ E x̄ = 0).
//!
//! Five correspondences leave a 4-dimensional null space E = x X + y Y + z Z + W. The cubic
//! constraints det E = 0 and 2 E Eᵀ E − tr(E Eᵀ) E = 0 give ten equations in the twenty
//! monomials of degree ≤ 3 in (x, y, z). Gauss–Jordan elimination expresses the ten cubic
//! monomials through the ten of lower degree; multiplication by x then acts linearly on those ten
//! (the action matrix), and its real eigenvectors are the solutions. Unlike the eight-point
//! algorithm it also works when the points lie on a plane, which is what a superpixel and its
//! neighbours often are.

use nalgebra::{Matrix3, SMatrix, Schur};

use super::Correspondence;

/// Monomials of degree ≤ 3 in (x, y, z) as exponent triples: the ten cubic ones first (these are
/// eliminated), then the ten of lower degree (the basis the action matrix works on).
const MONOMIALS: [[u8; 3]; 20] = [
    [3, 0, 0],
    [2, 1, 0],
    [2, 0, 1],
    [1, 2, 0],
    [1, 1, 1],
    [1, 0, 2],
    [0, 3, 0],
    [0, 2, 1],
    [0, 1, 2],
    [0, 0, 3],
    [2, 0, 0],
    [1, 1, 0],
    [1, 0, 1],
    [0, 2, 0],
    [0, 1, 1],
    [0, 0, 2],
    [1, 0, 0],
    [0, 1, 0],
    [0, 0, 1],
    [0, 0, 0],
];

/// Position of a monomial in [`MONOMIALS`].
const fn index_of(e: [u8; 3]) -> Option<usize> {
    let mut i = 0;
    while i < MONOMIALS.len() {
        let m = MONOMIALS[i];
        if m[0] == e[0] && m[1] == e[1] && m[2] == e[2] {
            return Some(i);
        }
        i += 1;
    }
    None
}

/// `PRODUCT[i][j]`: the position of monomial i times monomial j, or `NO_TERM` above degree 3.
const PRODUCT: [[u8; 20]; 20] = {
    let mut table = [[NO_TERM; 20]; 20];
    let mut i = 0;
    while i < 20 {
        let mut j = 0;
        while j < 20 {
            let (a, b) = (MONOMIALS[i], MONOMIALS[j]);
            if let Some(k) = index_of([a[0] + b[0], a[1] + b[1], a[2] + b[2]]) {
                table[i][j] = k as u8;
            }
            j += 1;
        }
        i += 1;
    }
    table
};

const NO_TERM: u8 = u8::MAX;

/// A polynomial of degree ≤ 3 in (x, y, z): coefficients in the order of [`MONOMIALS`].
#[derive(Clone, Copy, Debug)]
struct Poly([f64; 20]);

impl Poly {
    const ZERO: Poly = Poly([0.0; 20]);

    /// The linear polynomial a·x + b·y + c·z + d.
    fn linear(a: f64, b: f64, c: f64, d: f64) -> Poly {
        let mut p = Poly::ZERO;
        p.0[16] = a;
        p.0[17] = b;
        p.0[18] = c;
        p.0[19] = d;
        p
    }

    fn add(&self, o: &Poly) -> Poly {
        let mut p = *self;
        p.0.iter_mut().zip(o.0).for_each(|(a, b)| *a += b);
        p
    }

    fn scale(&self, s: f64) -> Poly {
        Poly(self.0.map(|a| a * s))
    }

    /// The product; terms above degree 3 cannot occur for the products used here and are dropped.
    fn mul(&self, o: &Poly) -> Poly {
        let mut p = Poly::ZERO;
        let nonzero: Vec<(usize, f64)> =
            o.0.iter()
                .enumerate()
                .filter(|&(_, &b)| b != 0.0)
                .map(|(j, &b)| (j, b))
                .collect();
        for (i, &a) in self.0.iter().enumerate() {
            if a == 0.0 {
                continue;
            }
            for &(j, b) in &nonzero {
                let k = PRODUCT[i][j];
                if k != NO_TERM {
                    p.0[k as usize] += a * b;
                }
            }
        }
        p
    }
}

type PolyMatrix = [[Poly; 3]; 3];

fn poly_mat_mul(a: &PolyMatrix, b: &PolyMatrix) -> PolyMatrix {
    let mut out = [[Poly::ZERO; 3]; 3];
    for (r, row) in out.iter_mut().enumerate() {
        for (c, cell) in row.iter_mut().enumerate() {
            for k in 0..3 {
                *cell = cell.add(&a[r][k].mul(&b[k][c]));
            }
        }
    }
    out
}

fn transpose(a: &PolyMatrix) -> PolyMatrix {
    let mut out = [[Poly::ZERO; 3]; 3];
    for (r, row) in out.iter_mut().enumerate() {
        for (c, cell) in row.iter_mut().enumerate() {
            *cell = a[c][r];
        }
    }
    out
}

/// The up to ten essential matrices consistent with five correspondences (each with singular
/// values (1, 1, 0) up to scale). More than five points are accepted; only the first five are
/// used. Empty for fewer points or a degenerate configuration.
pub fn five_point(points: &[Correspondence]) -> Vec<Matrix3<f64>> {
    if points.len() < 5 {
        return Vec::new();
    }
    let Some(basis) = null_space(&points[..5]) else {
        return Vec::new();
    };
    let e: PolyMatrix = std::array::from_fn(|r| {
        std::array::from_fn(|c| {
            let i = 3 * r + c;
            Poly::linear(basis[0][i], basis[1][i], basis[2][i], basis[3][i])
        })
    });
    let equations = constraints(&e);
    let Some(reduced) = eliminate(equations) else {
        return Vec::new();
    };
    solutions(&reduced)
        .into_iter()
        .map(|(x, y, z)| {
            Matrix3::from_fn(|r, c| {
                let i = 3 * r + c;
                x * basis[0][i] + y * basis[1][i] + z * basis[2][i] + basis[3][i]
            })
        })
        .filter(|m| m.iter().all(|v| v.is_finite()))
        .map(|m| m / m.norm())
        .collect()
}

/// The four vectors (E flattened row by row) spanning the null space of the 5 × 9 epipolar system.
fn null_space(points: &[Correspondence]) -> Option<[[f64; 9]; 4]> {
    let mut a = SMatrix::<f64, 9, 9>::zeros();
    for (row, c) in points.iter().enumerate() {
        for r in 0..3 {
            for col in 0..3 {
                a[(row, 3 * r + col)] = c.x2[r] * c.x1[col];
            }
        }
    }
    if a.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let svd = a.svd(false, true);
    let v_t = svd.v_t?;
    // Singular values come sorted in decreasing order: the last four rows span the null space.
    let mut order: Vec<usize> = (0..9).collect();
    order.sort_by(|&i, &j| svd.singular_values[j].total_cmp(&svd.singular_values[i]));
    if svd.singular_values[order[4]] < 1e-12 * svd.singular_values[order[0]] {
        return None; // fewer than five independent constraints
    }
    Some(std::array::from_fn(|k| {
        let row = v_t.row(order[5 + k]);
        std::array::from_fn(|i| row[i])
    }))
}

/// The ten cubic equations: det E = 0 and the nine entries of 2 E Eᵀ E − tr(E Eᵀ) E = 0.
fn constraints(e: &PolyMatrix) -> [[f64; 20]; 10] {
    let eet = poly_mat_mul(e, &transpose(e));
    let trace = eet[0][0].add(&eet[1][1]).add(&eet[2][2]);
    let eete = poly_mat_mul(&eet, e);
    let mut out = [[0.0; 20]; 10];
    let det = e[0][0]
        .mul(
            &e[1][1]
                .mul(&e[2][2])
                .add(&e[1][2].mul(&e[2][1]).scale(-1.0)),
        )
        .add(
            &e[0][1].mul(
                &e[1][2]
                    .mul(&e[2][0])
                    .add(&e[1][0].mul(&e[2][2]).scale(-1.0)),
            ),
        )
        .add(
            &e[0][2].mul(
                &e[1][0]
                    .mul(&e[2][1])
                    .add(&e[1][1].mul(&e[2][0]).scale(-1.0)),
            ),
        );
    out[0] = det.0;
    for r in 0..3 {
        for c in 0..3 {
            out[1 + 3 * r + c] = eete[r][c]
                .scale(2.0)
                .add(&trace.mul(&e[r][c]).scale(-1.0))
                .0;
        }
    }
    out
}

/// Gauss–Jordan elimination with partial pivoting of the 10 × 20 system; returns the 10 × 10
/// block C with cubic_j = −Σ_k C_jk · basis_k. `None` when the cubic block is singular.
fn eliminate(mut m: [[f64; 20]; 10]) -> Option<[[f64; 10]; 10]> {
    for col in 0..10 {
        let pivot = (col..10).max_by(|&a, &b| m[a][col].abs().total_cmp(&m[b][col].abs()))?;
        let scale = m.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
        if m[pivot][col].abs() <= 1e-12 * scale.max(1e-300) {
            return None;
        }
        m.swap(col, pivot);
        let p = m[col][col];
        m[col].iter_mut().for_each(|v| *v /= p);
        for row in 0..10 {
            if row != col {
                let f = m[row][col];
                if f != 0.0 {
                    let pivot_row = m[col];
                    for (v, p) in m[row].iter_mut().zip(pivot_row).skip(col) {
                        *v -= f * p;
                    }
                }
            }
        }
    }
    Some(std::array::from_fn(|r| {
        std::array::from_fn(|k| m[r][10 + k])
    }))
}

/// Real solutions (x, y, z) from the real eigenvectors of the action matrix of multiplication by x.
fn solutions(c: &[[f64; 10]; 10]) -> Vec<(f64, f64, f64)> {
    // Row r of the action matrix writes x · basis_r in the basis (monomials 10..20).
    let mut action = SMatrix::<f64, 10, 10>::zeros();
    for r in 0..10 {
        let b = MONOMIALS[10 + r];
        let Some(target) = index_of([b[0] + 1, b[1], b[2]]) else {
            return Vec::new();
        };
        if target >= 10 {
            action[(r, target - 10)] = 1.0;
        } else {
            for k in 0..10 {
                action[(r, k)] = -c[target][k];
            }
        }
    }
    if action.iter().any(|v| !v.is_finite()) {
        return Vec::new();
    }
    let Some(schur) = Schur::try_new(action, 1e-14, 500) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for ev in schur.complex_eigenvalues().iter() {
        if ev.im.abs() > 1e-8 * (1.0 + ev.re.abs()) {
            continue;
        }
        // The eigenvector with its last entry (the monomial 1) fixed to 1: least squares on
        // (M − λI) v = 0 for the other nine entries.
        let shifted = action - SMatrix::<f64, 10, 10>::identity() * ev.re;
        let qr = shifted.fixed_view::<10, 9>(0, 0).clone_owned().qr();
        let rhs = -(qr.q().transpose() * shifted.column(9));
        let Some(v) = qr.r().solve_upper_triangular(&rhs) else {
            continue;
        };
        out.push((v[6], v[7], v[8]));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::essential::{Motion, decompose};
    use crate::rng::Rng;
    use nalgebra::{Rotation3, Vector3};

    fn motion() -> Motion {
        Motion {
            r: Rotation3::from_euler_angles(0.02, -0.05, 0.01).into_inner(),
            t: Vector3::new(0.3, -0.1, 0.9).normalize(),
        }
    }

    /// Correspondences of 3D points under `m`; `planar` puts them on one plane.
    fn points(m: &Motion, n: usize, planar: bool, rng: &mut Rng) -> Vec<Correspondence> {
        (0..n)
            .map(|_| {
                let (u, v) = (rng.uniform() * 2.0 - 1.0, rng.uniform() * 2.0 - 1.0);
                let z = if planar {
                    // The plane 0.1 x + 0.2 y + z = 5 (slanted, in front of both cameras).
                    5.0 / (1.0 + 0.1 * u + 0.2 * v)
                } else {
                    3.0 + 6.0 * rng.uniform()
                };
                let x = Vector3::new(u * z, v * z, z);
                let x2 = m.r * x + m.t;
                Correspondence {
                    x1: x / x.z,
                    x2: x2 / x2.z,
                }
            })
            .collect()
    }

    /// The smallest distance between the true essential matrix and a solution (both unit norm,
    /// sign-free).
    fn closest(truth: &Matrix3<f64>, solutions: &[Matrix3<f64>]) -> f64 {
        let t = truth / truth.norm();
        solutions
            .iter()
            .map(|e| (e - t).norm().min((e + t).norm()))
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn recovers_the_true_essential_matrix() {
        let m = motion();
        let mut rng = Rng::new(11);
        for _ in 0..20 {
            let pts = points(&m, 5, false, &mut rng);
            let sols = five_point(&pts);
            assert!(
                !sols.is_empty() && sols.len() <= 10,
                "{} solutions",
                sols.len()
            );
            assert!(closest(&m.essential(), &sols) < 1e-6);
            for e in &sols {
                // Every solution satisfies the five constraints and is essential.
                assert!(pts.iter().all(|c| c.x2.dot(&(e * c.x1)).abs() < 1e-9));
                let eet = e * e.transpose();
                assert!((2.0 * eet * e - eet.trace() * e).norm() < 1e-8);
            }
        }
    }

    #[test]
    fn works_on_a_plane_where_eight_points_fail() {
        let m = motion();
        let pts = points(&m, 5, true, &mut Rng::new(12));
        let sols = five_point(&pts);
        assert!(
            closest(&m.essential(), &sols) < 1e-6,
            "{} solutions",
            sols.len()
        );
        let checks = points(&m, 50, true, &mut Rng::new(13));
        let best = sols
            .iter()
            .filter_map(|e| decompose(e, &checks))
            .map(|got| (got.r - m.r).norm() + (got.t - m.t).norm())
            .fold(f64::INFINITY, f64::min);
        assert!(best < 1e-6, "{best}");
    }

    #[test]
    fn degenerate_input_gives_no_solution() {
        let c = Correspondence {
            x1: Vector3::new(0.1, 0.2, 1.0),
            x2: Vector3::new(0.1, 0.2, 1.0),
        };
        assert!(five_point(&[c; 5]).is_empty());
        assert!(five_point(&[c; 4]).is_empty());
        let nan = Correspondence {
            x1: Vector3::new(f64::NAN, 0.0, 1.0),
            ..c
        };
        assert!(five_point(&[nan; 5]).is_empty());
    }
}
