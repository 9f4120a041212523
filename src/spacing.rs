//! The even sample of a cloud that the far-outlier test ([`crate::outliers`]) and the
//! support-plane test ([`crate::support`]) both look at: at most [`SAMPLE`] points, their k-d
//! tree, and each point's *reach*, the distance to its [`NEIGHBOUR`]th nearest other sample point,
//! whose median is the sample's spacing. Built once per cloud and shared by the two tests while
//! the cloud is unchanged.

use crate::refine::even_sample;
use crate::spatial::KdIndex;

/// Most points of the even sample.
pub const SAMPLE: usize = 2048;

/// The neighbour (by rank among the other sample points) whose distance is a point's reach.
pub const NEIGHBOUR: usize = 4;

/// An even sample of a cloud with its k-d tree and reaches (see the module docs).
#[derive(Debug)]
pub struct Spacing {
    /// At most [`SAMPLE`] points spread evenly over the cloud.
    pub sample: Vec<[f32; 3]>,
    /// The sample's k-d tree.
    pub index: KdIndex,
    /// Per sample point, the distance to its [`NEIGHBOUR`]th nearest other sample point (the
    /// farthest when the sample has fewer; infinite when the distances overflow `f32`).
    pub reach: Vec<f32>,
    /// The median reach: the sample's spacing (infinite for an empty sample).
    pub median: f32,
}

impl Spacing {
    /// The sample points whose reach is at most `factor` times the median: those that stand
    /// among others, not isolated strays.
    pub fn settled(&self, factor: f32) -> impl Iterator<Item = &[f32; 3]> + '_ {
        let limit = factor * self.median;
        self.sample.iter().zip(&self.reach).filter(move |(_, &r)| r <= limit).map(|(p, _)| p)
    }

    /// The sample of `points`, its tree and reaches.
    pub fn of(points: &[[f32; 3]]) -> Self {
        let sample = even_sample(points, SAMPLE);
        let index = KdIndex::new(&sample);
        let mut out = Vec::with_capacity(NEIGHBOUR + 1);
        // the nearest found is the point itself; a point so far from the others that their squared
        // distances overflow f32 (a stray at 1e20, a sensor's f32::MAX for "no return") finds only
        // itself, and its reach is infinite
        let wanted = (NEIGHBOUR + 1).min(sample.len());
        let reach: Vec<f32> = sample
            .iter()
            .map(|q| {
                index.knn_into(q, NEIGHBOUR + 1, &mut out);
                match out.last() {
                    Some(e) if out.len() == wanted => e.1.sqrt(),
                    _ => f32::INFINITY,
                }
            })
            .collect();
        let median = if reach.is_empty() {
            f32::INFINITY
        } else {
            let mut sorted = reach.clone();
            let mid = sorted.len() / 2;
            *sorted.select_nth_unstable_by(mid, f32::total_cmp).1
        };
        Self { sample, index, reach, median }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_grids_reach_is_its_spacing_and_a_large_cloud_is_sampled() {
        // a 40 x 40 grid of spacing 0.5: the 4th nearest other point is an axis neighbour
        let grid: Vec<[f32; 3]> = (0..1600).map(|i| [(i % 40) as f32 * 0.5, (i / 40) as f32 * 0.5, 0.0]).collect();
        let s = Spacing::of(&grid);
        assert_eq!((s.sample.len(), s.index.len(), s.reach.len()), (1600, 1600, 1600));
        assert_eq!(s.median, 0.5);
        // a corner's 4th nearest other point is a diagonal or second neighbour
        assert!(s.reach[0] > 0.5);
        let big: Vec<[f32; 3]> = (0..10_000).map(|i| [i as f32, 0.0, 0.0]).collect();
        assert_eq!(Spacing::of(&big).sample.len(), SAMPLE);
        let empty = Spacing::of(&[]);
        assert!(empty.sample.is_empty() && empty.median.is_infinite());
        // a point whose squared distances to the others overflow f32 has an infinite reach
        let mut strays = grid.clone();
        strays.push([1e20, 0.0, 0.0]);
        strays.push([0.0, 3e38, 0.0]);
        let s = Spacing::of(&strays);
        assert!(s.reach[1600].is_infinite() && s.reach[1601].is_infinite(), "{:?}", &s.reach[1600..]);
        assert_eq!(s.median, 0.5);
    }
}
