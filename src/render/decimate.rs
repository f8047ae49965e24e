//! Deterministic decimation of a point cloud to a point budget.
//!
//! A reconstruction has one point per pixel, so its points come in image order. Taking every
//! k-th point would leave regular stripes (whenever k shares a factor with the image width);
//! instead each point is kept with the right probability by selection sampling
//! (Knuth, TAOCP vol. 2, Algorithm S) from a fixed-seed generator: exactly `budget` points,
//! spread evenly without a pattern, in their original order, the same on every run.

use crate::rng::Rng;

/// Seed of the sampling stream; fixed so that the same cloud always shows the same points.
const DECIMATION_SEED: u64 = 0x7669_6577_6572; // "viewer" in ASCII

/// Default point budget on desktop browsers: a 1024 × 1024 reconstruction is drawn whole.
pub const DESKTOP_POINT_BUDGET: usize = 1 << 20;

/// Default point budget on phones and tablets (coarse pointer), where fill rate is scarce.
pub const MOBILE_POINT_BUDGET: usize = 300_000;

/// Indices (ascending) of the points of a cloud of `len` points to draw under `budget`:
/// all of them when `len ≤ budget`, otherwise exactly `budget` of them chosen uniformly.
pub fn decimate(len: usize, budget: usize) -> Vec<u32> {
    if len <= budget {
        return (0..len as u32).collect();
    }
    let mut rng = Rng::new(DECIMATION_SEED);
    let mut kept = Vec::with_capacity(budget);
    for i in 0..len {
        // Keep point i with probability (still needed) / (still left).
        let needed = budget - kept.len();
        if needed == 0 {
            break;
        }
        let left = len - i;
        if rng.below(left) < needed {
            kept.push(i as u32);
        }
    }
    kept
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_clouds_are_kept_whole() {
        assert_eq!(decimate(5, 10), vec![0, 1, 2, 3, 4]);
        assert_eq!(decimate(10, 10).len(), 10);
        assert!(decimate(0, 10).is_empty());
    }

    #[test]
    fn large_clouds_keep_exactly_the_budget_in_order() {
        for (len, budget) in [(1000, 1), (1000, 999), (100_000, 12_345), (7, 0)] {
            let kept = decimate(len, budget);
            assert_eq!(kept.len(), budget);
            assert!(kept.windows(2).all(|w| w[0] < w[1]));
            assert!(kept.iter().all(|&i| (i as usize) < len));
        }
    }

    #[test]
    fn kept_points_are_spread_evenly() {
        // 100 × 100 "image", keep a quarter: every block of 10 rows keeps about a quarter, and
        // no column is starved (a stride of 4 would keep only every 4th column).
        let (w, h) = (100usize, 100usize);
        let kept = decimate(w * h, w * h / 4);
        let mut per_band = [0usize; 10];
        let mut per_column = vec![0usize; w];
        for &i in &kept {
            per_band[i as usize / w / 10] += 1;
            per_column[i as usize % w] += 1;
        }
        assert!(
            per_band.iter().all(|&n| (200..=300).contains(&n)),
            "{per_band:?}"
        );
        assert!(
            per_column.iter().all(|&n| (10..=45).contains(&n)),
            "{per_column:?}"
        );
    }
}
