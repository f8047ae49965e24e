//! Seeded RANSAC: the model with the most inliers over random minimal samples.

use crate::rng::Rng;

/// RANSAC settings.
#[derive(Clone, Copy, Debug)]
pub struct RansacParams {
    /// Points in a minimal sample.
    pub sample_size: usize,
    /// Number of samples drawn.
    pub iterations: usize,
    /// A point is an inlier when its error is below this (in the error's own units).
    pub threshold: f64,
}

/// Runs RANSAC over `n` points, drawing samples from `pool` (point indices; all points when
/// `None`) and counting inliers over all points: `fit` turns a sample into candidate models,
/// `error` scores one point under a model. Returns the model with the most inliers (the first on
/// a tie) and its inlier indices, or `None` when no sample gave a model or there are fewer points
/// than a sample. Local optimisation is the caller's (see `essential::robust_motion`).
pub fn ransac<M>(
    n: usize,
    pool: Option<&[usize]>,
    params: &RansacParams,
    rng: &mut Rng,
    mut fit: impl FnMut(&[usize]) -> Vec<M>,
    error: impl Fn(&M, usize) -> f64,
) -> Option<(M, Vec<usize>)> {
    let pool_len = pool.map_or(n, <[usize]>::len);
    if pool_len < params.sample_size || params.sample_size == 0 {
        return None;
    }
    let mut best: Option<(M, usize)> = None;
    for _ in 0..params.iterations {
        let mut sample = rng.sample_distinct(pool_len, params.sample_size);
        if let Some(pool) = pool {
            sample.iter_mut().for_each(|i| *i = pool[*i]);
        }
        for model in fit(&sample) {
            let count = (0..n)
                .filter(|&i| error(&model, i) < params.threshold)
                .count();
            if best.as_ref().is_none_or(|b| count > b.1) {
                best = Some((model, count));
            }
        }
    }
    let (model, _) = best?;
    let inliers = (0..n)
        .filter(|&i| error(&model, i) < params.threshold)
        .collect();
    Some((model, inliers))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_a_line_among_outliers() {
        // y = 2x + 1 for 60 points, 40 random outliers.
        let mut rng = Rng::new(5);
        let pts: Vec<(f64, f64)> = (0..100)
            .map(|i| {
                let x = i as f64 * 0.1;
                if i % 5 < 3 {
                    (x, 2.0 * x + 1.0)
                } else {
                    (x, rng.uniform() * 30.0)
                }
            })
            .collect();
        let params = RansacParams {
            sample_size: 2,
            iterations: 100,
            threshold: 1e-6,
        };
        let (line, inliers) = ransac(
            pts.len(),
            None,
            &params,
            &mut Rng::new(9),
            |s| {
                let ((x0, y0), (x1, y1)) = (pts[s[0]], pts[s[1]]);
                if (x1 - x0).abs() < 1e-12 {
                    vec![]
                } else {
                    vec![((y1 - y0) / (x1 - x0), y0 - x0 * (y1 - y0) / (x1 - x0))]
                }
            },
            |&(a, b): &(f64, f64), i| (pts[i].1 - a * pts[i].0 - b).abs(),
        )
        .unwrap();
        assert!((line.0 - 2.0).abs() < 1e-9 && (line.1 - 1.0).abs() < 1e-9);
        assert_eq!(inliers.len(), 60);
    }
}
