//! The hinted search's shortcut: the hint's own nearest neighbours, and how far the rest lie.
//!
//! In an ICP pass every moved source point asks for its nearest target point, with its partner of
//! the previous pass as the hint, and in late iterations the answer is almost always that partner
//! or one of its neighbours. A hinted search that scans the hint's whole leaf ([`super::LEAF`]
//! points) and climbs does more work than that needs.
//!
//! So the index keeps, for each point that has been a hint, a [`Neighbourhood`]: its
//! [`NEIGHBOURS`] nearest other points and `reach`, the distance of the farthest of them (every
//! other point is at least that far from it). For a query `q` and hint `p`, the triangle
//! inequality puts every point outside the neighbourhood at least `reach - |q - p|` from `q`.
//! When the nearest of `p` and its neighbours is nearer than that, it is the nearest of all:
//! found with [`NEIGHBOURS`]` + 1` distances. Otherwise the search goes on as before. The answer
//! is the tree's either way (among points at exactly equal distance, possibly another).
//!
//! A neighbourhood is found (a k-nearest search) the first time its point is a hint and kept; the
//! table of them is allocated at the first hinted search, and only for indices of at most
//! [`MAX_POINTS`] points, so it adds at most [`MAX_POINTS`] x [`BYTES_PER_POINT`] to an index.

use super::{dist2, Floors, KdIndex};
use std::cmp::Ordering;
use std::sync::OnceLock;

/// Neighbours kept per point: with the point itself, the 20 nearest points that point-to-plane
/// ICP fits a target normal to ([`crate::icp::NORMAL_NEIGHBOURS`]), so one search serves both
/// ([`KdIndex::neighbours`]). They answer about three in four of ICP's hinted searches on
/// 4,096-point any-pose pairs (`BENCHMARK.md`, "The hint's neighbourhood").
pub const NEIGHBOURS: usize = 19;

/// Largest index (in points) that keeps neighbourhoods; larger ones search the tree from the
/// hint's leaf only. The default voxelisation leaves ICP's clouds of a few hundred thousand
/// points at most.
pub const MAX_POINTS: usize = 1 << 18;

/// Memory of one point's entry in the table, found or not.
pub const BYTES_PER_POINT: usize = std::mem::size_of::<OnceLock<Neighbourhood>>();

/// A point's [`NEIGHBOURS`] nearest other points (positions in the index; `u32::MAX` where the
/// index holds fewer) and how far the rest lie.
#[derive(Clone, Copy, Debug)]
pub struct Neighbourhood {
    at: [u32; NEIGHBOURS],
    /// A lower bound of the distance from the point to every other point not listed (the
    /// farthest listed one's, lowered by [`MARGIN`]; infinite when every other point is listed).
    reach: f32,
}

/// Relative margin by which the distances behind a bound are moved towards a smaller bound:
/// they are computed in `f32`, a few units in the last place off.
const MARGIN: f32 = 1e-5;

impl KdIndex {
    /// The neighbourhood of the point at position `p`, found now if it was not yet; `None` when
    /// the index keeps none ([`MAX_POINTS`]).
    fn neighbourhood(&self, p: u32) -> Option<&Neighbourhood> {
        if self.count > MAX_POINTS {
            return None;
        }
        let table = self.neighbourhoods.get_or_init(|| (0..self.ids.len()).map(|_| OnceLock::new()).collect());
        Some(table[p as usize].get_or_init(|| {
            let mut near = Vec::with_capacity(NEIGHBOURS + 1);
            self.knn_positions(&self.point(p), NEIGHBOURS + 1, &mut near);
            let mut at = [u32::MAX; NEIGHBOURS];
            // the point itself is among its nearest (unless it has duplicates): the others, up to
            // NEIGHBOURS of them
            for (slot, &(o, _)) in at.iter_mut().zip(near.iter().filter(|e| e.0 != p as usize)) {
                *slot = o as u32;
            }
            // every point not found is at least as far as the farthest found
            let all = near.len() == self.count;
            let reach = match near.last() {
                Some(&(_, d2)) if !all => d2.sqrt() * (1.0 - MARGIN),
                _ => f32::INFINITY,
            };
            Neighbourhood { at, reach }
        }))
    }

    /// The [`NEIGHBOURS`] points nearest to the indexed point `j` other than itself (their
    /// indices), nearest first in the order of [`KdIndex::knn_into`] (so `j` and these are the
    /// `NEIGHBOURS + 1` nearest points to `j`, itself first unless it has duplicates); fewer when
    /// the index holds fewer. Found now if they were not yet, and kept; `None` when the index
    /// keeps no neighbourhoods ([`MAX_POINTS`]) or does not hold `j`.
    pub fn neighbours(&self, j: usize) -> Option<impl Iterator<Item = usize> + Clone + '_> {
        let p = *self.pos.get(j).filter(|&&p| p != u32::MAX)?;
        let n = self.neighbourhood(p)?;
        Some(n.at.iter().take_while(|&&o| o != u32::MAX).map(|&o| self.ids[o as usize] as usize))
    }

    /// The nearest point to `q` strictly within `max_d2`, when the neighbourhood of the hint at
    /// position `p` shows which it is: `Some(best)` with `best` as the search keeps it (its
    /// position and squared distance; `(u32::MAX, max_d2)` when it is beyond `max_d2`); the least
    /// distance to the hint and its neighbours and a bound below every other point are then
    /// recorded in `floors` (with `FLOOR`), which must hold nothing yet. `None` (nothing recorded)
    /// when the neighbourhood cannot tell.
    #[inline(always)]
    pub(super) fn nearest_from_neighbourhood<const FLOOR: bool>(
        &self,
        p: u32,
        q: &[f32; 3],
        max_d2: f32,
        floors: &mut Floors,
    ) -> Option<(u32, f32)> {
        let n = self.neighbourhood(p)?;
        let hint_d2 = dist2(&self.point(p), q);
        // every point outside the neighbourhood is at least `gap` from `q`
        let gap = n.reach - hint_d2.sqrt() * (1.0 + MARGIN);
        // (a NaN bound tells nothing either)
        if gap.partial_cmp(&0.0) != Some(Ordering::Greater) {
            return None;
        }
        let gap2 = gap * gap * (1.0 - MARGIN);
        let (mut best, mut second) = ((p, hint_d2), f32::INFINITY);
        for &o in &n.at {
            if o == u32::MAX {
                break;
            }
            let d2 = dist2(&self.point(o), q);
            // ties to the earlier position, as a leaf's scan
            if d2 < best.1 || (d2 == best.1 && o < best.0) {
                second = best.1;
                best = (o, d2);
            } else if d2 < second {
                second = d2;
            }
        }
        if best.1.partial_cmp(&gap2) != Some(Ordering::Less) {
            return None;
        }
        floors.record::<FLOOR>(best.1);
        floors.record::<FLOOR>(if second < gap2 { second } else { gap2 });
        Some(if best.1 < max_d2 { best } else { (u32::MAX, max_d2) })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cloud(n: usize) -> Vec<[f32; 3]> {
        let mut s = 0x2545_f491_4f6c_dd1du64;
        let mut r = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 40) as f32 / (1u64 << 24) as f32
        };
        (0..n).map(|_| [r(), r(), r() * 0.05]).collect()
    }

    #[test]
    fn a_neighbourhood_lists_the_nearest_others_and_bounds_the_rest() {
        let pts = cloud(500);
        let idx = KdIndex::new(&pts);
        for j in (0..pts.len()).step_by(7) {
            let p = idx.pos[j];
            let n = *idx.neighbourhood(p).unwrap();
            let listed: Vec<usize> = n.at.iter().map(|&o| idx.ids[o as usize] as usize).collect();
            assert!(!listed.contains(&j));
            let mut others: Vec<f32> = (0..pts.len()).filter(|&i| i != j).map(|i| dist2(&pts[i], &pts[j])).collect();
            others.sort_by(f32::total_cmp);
            let mut got: Vec<f32> = listed.iter().map(|&i| dist2(&pts[i], &pts[j])).collect();
            got.sort_by(f32::total_cmp);
            assert_eq!(got, others[..NEIGHBOURS]);
            for i in (0..pts.len()).filter(|i| *i != j && !listed.contains(i)) {
                assert!(dist2(&pts[i], &pts[j]).sqrt() >= n.reach);
            }
        }
    }

    #[test]
    fn a_point_and_its_neighbours_are_its_nearest_points_in_knn_order() {
        let pts = cloud(300);
        let idx = KdIndex::new(&pts);
        let mut knn = Vec::new();
        for (j, p) in pts.iter().enumerate() {
            idx.knn_into(p, NEIGHBOURS + 1, &mut knn);
            let with: Vec<usize> = std::iter::once(j).chain(idx.neighbours(j).unwrap()).collect();
            assert_eq!(with, knn.iter().map(|e| e.0).collect::<Vec<_>>());
        }
        assert!(idx.neighbours(pts.len()).is_none());
    }

    #[test]
    fn what_a_neighbourhood_answers_is_the_nearest_of_all() {
        let pts = cloud(2_000);
        let idx = KdIndex::new(&pts);
        let (mut answered, mut asked) = (0, 0);
        for j in (0..pts.len()).step_by(3) {
            for (k, scale) in [0.0f32, 0.002, 0.01, 0.05].into_iter().enumerate() {
                let q = std::array::from_fn(|a| pts[j][a] + scale * [0.7f32, -0.4, 0.5][(a + k + j) % 3]);
                let mut d2: Vec<(f32, usize)> = pts.iter().enumerate().map(|(i, p)| (dist2(p, &q), i)).collect();
                d2.sort_by(|a, b| a.0.total_cmp(&b.0));
                for bound in [f32::INFINITY, d2[0].0 * 0.5, d2[0].0 * 2.0 + 1e-9] {
                    let mut floors = Floors::NONE;
                    asked += 1;
                    let Some(best) = idx.nearest_from_neighbourhood::<true>(idx.pos[j], &q, bound, &mut floors) else {
                        continue;
                    };
                    answered += 1;
                    let floors = floors.merged();
                    if d2[0].0 < bound {
                        assert_eq!((idx.ids[best.0 as usize] as usize, best.1), (d2[0].1, d2[0].0));
                        assert_eq!(floors.least, d2[0].0);
                        assert!(floors.second <= d2[1].0, "the floor is below every other point");
                    } else {
                        assert_eq!(best, (u32::MAX, bound));
                        assert!(floors.least <= d2[0].0 && floors.least >= bound);
                    }
                }
            }
            // at the point itself the neighbourhood always tells
            let mut floors = Floors::NONE;
            assert!(idx.nearest_from_neighbourhood::<true>(idx.pos[j], &pts[j], f32::INFINITY, &mut floors).is_some());
        }
        assert!(answered > asked / 2, "{answered} of {asked}");
    }

    #[test]
    fn small_and_large_indices() {
        // fewer points than NEIGHBOURS: everything is listed and every query is answered
        let pts = cloud(5);
        let idx = KdIndex::new(&pts);
        let mut floors = Floors::NONE;
        let best = idx.nearest_from_neighbourhood::<true>(idx.pos[0], &[9.0, 9.0, 9.0], f32::INFINITY, &mut floors);
        let want = (0..5).map(|i| dist2(&pts[i], &[9.0, 9.0, 9.0])).fold(f32::INFINITY, f32::min);
        assert_eq!(best.map(|b| b.1), Some(want));
        // above MAX_POINTS the index keeps no table
        let mut big = cloud(MAX_POINTS + 1);
        big[0] = [0.5, 0.5, 0.0];
        let idx = KdIndex::new(&big);
        assert!(idx.neighbourhood(idx.pos[0]).is_none());
        assert!(idx.neighbourhoods.get().is_none());
        assert_eq!(idx.nearest_within(&[0.5, 0.5, 0.0], 1.0, Some(0)).map(|r| r.1), Some(0.0));
    }
}
