//! Far outliers: points that lie far out from the rest of their cloud (a scanner's stray returns,
//! reflections, mixed pixels at depth edges), which registration leaves out
//! ([`Outliers::Drop`], the default).
//!
//! A few of them spoil every stage that looks at the cloud as a whole. The normalisation takes
//! the clouds' bounding boxes: 5% of the points scattered three times as far out as the object
//! make it three times too large, so the network sees a small object in a cloud of noise, and
//! the descriptors' voxel and ICP's distances grow with the box (`BENCHMARK.md`, "Far
//! outliers").
//!
//! The test is local density on an even sample of the cloud ([`Spacing`]: at most
//! [`crate::spacing::SAMPLE`] points, so the cost is one pass over the cloud plus two small k-d
//! trees): a sample point whose [`NEIGHBOUR`]th nearest sample point is more than [`ISOLATION`]
//! times the sample's median such distance away is isolated. The others span the *inlier box*,
//! widened on every side by [`MARGIN`] median distances. A point outside the box is a far outlier
//! unless [`NEIGHBOUR`] other points outside lie within [`SUPPORT`] median distances of it (scaled
//! to the whole cloud's density): then it is part of a structure (a far wall of a scan, the tip of
//! a thin part, another object) and stays. Isolated points inside the box stay too (they do not
//! move the box, and ICP's distance cut ignores them). Nothing is left out when more than
//! [`MAX_SHARE`] of the cloud would be. A cloud with no point outside the box is left exactly as it
//! is: all but about 0.2% of the validation sets' clean clouds, which lose one to four isolated
//! points each.

use crate::cloud::{grow_box, PointCloud, MIN_POINTS};
use crate::spacing::{self, Spacing};
use crate::spatial::KdIndex;
use serde::{Deserialize, Serialize};

/// What registration does with the points that lie far out from the rest of their cloud
/// (`Options::outliers`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
#[cfg_attr(feature = "ts", derive(ts_rs::TS), ts(rename = "Outliers"))]
pub enum Outliers {
    /// Leave them out, with a warning that says how many (the default).
    #[default]
    Drop,
    /// Keep every point.
    Keep,
}

/// The neighbour (by rank among the other sample points) whose distance measures a sample
/// point's isolation (its reach, [`Spacing`]), and how many others a point outside the inlier box
/// needs near it to stay: 4, so that two or three strays close together do not count as a
/// structure.
pub const NEIGHBOUR: usize = spacing::NEIGHBOUR;

/// How many times the sample's median [`NEIGHBOUR`] distance a sample point's own must exceed
/// to be isolated.
pub const ISOLATION: f32 = 8.0;

/// The inlier box's margin on every side, in the sample's median [`NEIGHBOUR`] distances. What
/// lies within it stays and still sets the cloud's bounding box; a tighter box (4 and 2 instead
/// of 8 and 8) takes more of the strays near the object away but also the sparse tips of thin
/// parts (a wing, a sword) of about 2% of the clean validation clouds (`BENCHMARK.md`, "Far
/// outliers").
pub const MARGIN: f32 = 8.0;

/// The radius within which a point outside the inlier box needs [`NEIGHBOUR`] others outside
/// it to stay (a structure, not a stray), in the sample's median [`NEIGHBOUR`] distances,
/// brought to the whole cloud's density.
pub const SUPPORT: f32 = 8.0;

/// Most points the box may leave out, as a share of the cloud: beyond it the box is not
/// telling stray points from the cloud (a scan whose density falls off steeply with range, a
/// sparse second object), and the cloud is left as it is.
pub const MAX_SHARE: f64 = 0.2;

/// The indices (ascending) of the far outliers of `points` (see the module docs); none when the
/// test does not apply (fewer than `NEIGHBOUR + 1` sample points, a median distance of zero,
/// more than [`MAX_SHARE`] of the points to leave out, fewer than [`MIN_POINTS`] to keep).
pub fn far_outliers(points: &[[f32; 3]]) -> Vec<usize> {
    far_outliers_with(points, &Spacing::of(points))
}

/// [`far_outliers`] with the sample of `points` already made (`spacing`, [`Spacing::of`] them).
pub fn far_outliers_with(points: &[[f32; 3]], spacing: &Spacing) -> Vec<usize> {
    let Spacing { sample, median, .. } = spacing;
    let median = *median;
    if sample.len() <= NEIGHBOUR || !(median > 0.0 && median.is_finite()) {
        return Vec::new();
    }
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for p in spacing.settled(ISOLATION) {
        grow_box(&mut lo, &mut hi, p);
    }
    let margin = MARGIN * median;
    let (lo, hi) = (lo.map(|v| v - margin), hi.map(|v| v + margin));
    let outside: Vec<usize> =
        (0..points.len()).filter(|&i| (0..3).any(|a| points[i][a] < lo[a] || points[i][a] > hi[a])).collect();
    if outside.is_empty() || outside.len() as f64 > MAX_SHARE * points.len() as f64 {
        return Vec::new();
    }
    // the points outside that lie on a structure (a far wall or ring of a scan, another
    // object, the tip of a thin part): NEIGHBOUR others outside within SUPPORT median distances,
    // brought to the whole cloud's density (a surface's spacing shrinks with the square root of
    // its point count)
    let radius = SUPPORT * median * (sample.len() as f32 / points.len() as f32).min(1.0).sqrt();
    let candidates: Vec<[f32; 3]> = outside.iter().map(|&i| points[i]).collect();
    let index = KdIndex::new(&candidates);
    let mut out = Vec::with_capacity(NEIGHBOUR + 2);
    let far: Vec<usize> = outside
        .iter()
        .zip(&candidates)
        .filter(|(_, q)| {
            index.within_into(q, radius * radius, NEIGHBOUR + 1, &mut out);
            out.len() <= NEIGHBOUR
        })
        .map(|(&i, _)| i)
        .collect();
    if points.len() - far.len() < MIN_POINTS {
        return Vec::new();
    }
    far
}

/// `cloud` without its far outliers ([`far_outliers`], removed in place) and how many were left
/// out.
pub fn drop_far(cloud: PointCloud) -> (PointCloud, usize) {
    let spacing = Spacing::of(&cloud.points);
    drop_far_with(cloud, &spacing)
}

/// [`drop_far`] with the sample of the cloud's points already made (`spacing`, [`Spacing::of`]
/// them).
pub fn drop_far_with(cloud: PointCloud, spacing: &Spacing) -> (PointCloud, usize) {
    let far = far_outliers_with(&cloud.points, spacing);
    let dropped = far.len();
    (if far.is_empty() { cloud } else { cloud.without(&far) }, dropped)
}

/// The warning for `dropped` far outliers of the cloud `what` of `total` points.
pub fn warning(what: &str, dropped: usize, total: usize) -> String {
    format!(
        "left out {dropped} of the {what}'s {total} points ({:.1}%): they lie far out from the rest of the cloud, sparser than it (stray returns, or the far end of a scan whose density falls with range); `outliers: \"keep\"` keeps them",
        100.0 * dropped as f64 / total.max(1) as f64
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `n` points on a wavy sheet of about 2 x 1.4 (a surface, as scans are).
    fn sheet(n: usize) -> Vec<[f32; 3]> {
        (0..n)
            .map(|i| {
                let (u, v) = ((i % 61) as f32 / 60.0, (i / 61) as f32 / (n / 61) as f32);
                [2.0 * u - 1.0, 1.4 * v - 0.7, 0.2 * (4.0 * u).sin() * (3.0 * v).cos()]
            })
            .collect()
    }

    /// A deterministic scatter of `n` points in the cube of half-side `half`.
    fn scatter(n: usize, half: f32) -> Vec<[f32; 3]> {
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            ((s >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0) * half
        };
        (0..n).map(|_| [next(), next(), next()]).collect()
    }

    #[test]
    fn a_clean_cloud_is_left_as_it_is() {
        let cloud = PointCloud::new(sheet(3_050));
        assert!(far_outliers(&cloud.points).is_empty());
        let (kept, dropped) = drop_far(cloud.clone());
        assert_eq!((kept.points, dropped), (cloud.points, 0));
    }

    #[test]
    fn points_scattered_far_out_are_left_out_and_the_surface_kept() {
        let surface = sheet(3_050);
        let mut points = surface.clone();
        // 5% scattered over a cube three times the sheet's size
        points.extend(scatter(150, 3.0));
        let (kept, dropped) = drop_far(PointCloud::with_origin(points.clone(), [1.0, 2.0, 3.0]));
        assert_eq!(kept.origin, [1.0, 2.0, 3.0]);
        // every surface point stays
        for p in &surface {
            assert!(kept.points.contains(p));
        }
        // most of the scatter goes; what stays lies near the sheet (within the box's margin)
        assert!(dropped >= 130 && kept.len() == points.len() - dropped, "dropped {dropped}");
        let (lo, hi) = kept.bounds();
        assert!(
            lo[0] > -1.6 && hi[0] < 1.6 && lo[1] > -1.3 && hi[1] < 1.3 && lo[2] > -0.8 && hi[2] < 0.8,
            "{lo:?} {hi:?}"
        );
    }

    #[test]
    fn strays_whose_distances_overflow_f32_are_left_out() {
        // a stray at 2e19 and a sensor's f32::MAX "no return": squared distances to them overflow
        let mut points = sheet(3_050);
        points.push([2e19, 0.0, 0.0]);
        points.push([0.0, f32::MAX, 0.0]);
        assert_eq!(far_outliers(&points), vec![3_050, 3_051]);
    }

    #[test]
    fn a_cluster_far_away_is_not_isolated() {
        // two patches far apart (two objects): both stay
        let mut points = sheet(3_050);
        points.extend(sheet(1_220).iter().map(|p| [p[0] + 10.0, p[1], p[2]]));
        assert!(far_outliers(&points).is_empty());
    }

    #[test]
    fn a_cloud_with_much_scatter_or_too_few_points_is_left_as_it_is() {
        // a third of the points scattered far out: more than MAX_SHARE would go
        let mut points = sheet(2_000);
        points.extend(scatter(1_000, 5.0));
        assert!(far_outliers(&points).is_empty());
        // too few points, or all of them on one spot but one
        assert!(far_outliers(&sheet(61)[..4]).is_empty());
        let mut spot = vec![[0.5f32; 3]; 100];
        spot.push([9.0, 9.0, 9.0]);
        assert!(far_outliers(&spot).is_empty());
    }
}
