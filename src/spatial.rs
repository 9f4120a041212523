//! A small nearest-neighbour index over `f32` xyz points: a thin wrapper around the `kiddo`
//! k-d tree (built once, queried many times), so the rest of the crate depends on one tiny API
//! rather than on a particular tree crate.
//!
//! `kiddo` is used with `default-features = false` (no rayon), so it builds for
//! `wasm32-unknown-unknown`. Queries are exact and deterministic: the same points give the same
//! tree and the same answers, ties included.

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use std::num::NonZeroUsize;

/// An immutable k-d tree over a point set; item `i` is the index of the point in the slice the
/// index was built from.
pub struct KdIndex {
    tree: Option<ImmutableKdTree<f32, 3>>,
    len: usize,
}

impl KdIndex {
    /// Builds the tree. An empty slice (or one too large for `u32` indices, which cannot happen
    /// for clouds that fit in memory on wasm32) gives an index that answers every query with
    /// nothing.
    pub fn new(points: &[[f32; 3]]) -> Self {
        if points.is_empty() || points.len() > u32::MAX as usize {
            return Self { tree: None, len: 0 };
        }
        match ImmutableKdTree::<f32, 3>::new_from_slice(points) {
            Ok(tree) => Self {
                tree: Some(tree),
                len: points.len(),
            },
            Err(_) => Self { tree: None, len: 0 },
        }
    }

    /// Number of indexed points.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when the index holds no points.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The nearest indexed point to `q`: `(index, squared distance)`, or `None` when the index
    /// is empty.
    #[inline]
    pub fn nearest(&self, q: &[f32; 3]) -> Option<(usize, f32)> {
        let tree = self.tree.as_ref()?;
        let r = tree.query(q).nearest_one::<SquaredEuclidean<f32>>().execute();
        Some((r.item as usize, r.distance))
    }

    /// The `k` nearest indexed points to `q` (fewer if the index is smaller), nearest first,
    /// written into `out` (cleared first) as indices.
    pub fn knn_into(&self, q: &[f32; 3], k: usize, out: &mut Vec<usize>) {
        out.clear();
        let (Some(tree), Some(k)) = (self.tree.as_ref(), NonZeroUsize::new(k.min(self.len))) else {
            return;
        };
        let found = tree.query(q).nearest_n::<SquaredEuclidean<f32>>(k).execute();
        out.extend(found.iter().map(|r| r.item as usize));
    }
}

impl std::fmt::Debug for KdIndex {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("KdIndex").field("len", &self.len).finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_and_knn_match_brute_force() {
        let pts: Vec<[f32; 3]> = (0..500)
            .map(|i| {
                let f = i as f32;
                [(f * 0.37).sin() * 3.0, (f * 0.11).cos() * 2.0, (f * 0.05).sin()]
            })
            .collect();
        let idx = KdIndex::new(&pts);
        assert_eq!(idx.len(), 500);
        let d2 = |a: &[f32; 3], b: &[f32; 3]| (0..3).map(|k| (a[k] - b[k]) * (a[k] - b[k])).sum::<f32>();
        let mut out = Vec::new();
        for q in [[0.1f32, 0.2, 0.3], [3.0, -2.0, 1.0], [-10.0, 0.0, 0.0]] {
            let (i, d) = idx.nearest(&q).unwrap();
            let best = pts.iter().map(|p| d2(p, &q)).fold(f32::INFINITY, f32::min);
            assert!((d - best).abs() <= 1e-6 * best.max(1.0), "{d} vs {best}");
            assert!((d2(&pts[i], &q) - best).abs() <= 1e-6 * best.max(1.0));
            idx.knn_into(&q, 7, &mut out);
            let mut all: Vec<f32> = pts.iter().map(|p| d2(p, &q)).collect();
            all.sort_by(f32::total_cmp);
            let got: Vec<f32> = out.iter().map(|&i| d2(&pts[i], &q)).collect();
            assert_eq!(got.len(), 7);
            for (g, w) in got.iter().zip(&all) {
                assert!((g - w).abs() <= 1e-6 * w.max(1.0));
            }
        }
    }

    #[test]
    fn empty_index_answers_nothing() {
        let idx = KdIndex::new(&[]);
        assert!(idx.is_empty());
        assert!(idx.nearest(&[0.0; 3]).is_none());
        let mut out = vec![1];
        idx.knn_into(&[0.0; 3], 3, &mut out);
        assert!(out.is_empty());
    }
}
