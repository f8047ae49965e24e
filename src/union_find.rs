//! Disjoint sets over `0..n` as a parent array (`parent[i] == i` at a root): the connected
//! components of SLIC's label runs and of the scale solve's rigid segments.

/// Root of `i`'s set, halving the path on the way.
pub(crate) fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

/// Joins the sets of `i` and `j`; the smaller root index becomes the root of both.
pub(crate) fn union(parent: &mut [usize], i: usize, j: usize) {
    let (a, b) = (find(parent, i), find(parent, j));
    parent[a.max(b)] = a.min(b);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joined_sets_share_the_smallest_root() {
        let mut parent: Vec<usize> = (0..6).collect();
        union(&mut parent, 4, 2);
        union(&mut parent, 2, 5);
        union(&mut parent, 1, 3);
        let roots: Vec<usize> = (0..6).map(|i| find(&mut parent, i)).collect();
        assert_eq!(roots, [0, 1, 2, 1, 2, 2]);
    }
}
