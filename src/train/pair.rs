//! One training pair, as the data pipeline hands it to [`super::train_step`].

use nalgebra::Matrix4;

/// A source/target pair with its ground truth.
#[derive(Clone, Debug, PartialEq)]
pub struct Pair {
    /// Source cloud, normalised units, N points.
    pub source: Vec<[f32; 3]>,
    /// Target cloud, normalised units, N points.
    pub target: Vec<[f32; 3]>,
    /// Ground truth `T_target_source` (maps source points into the target frame).
    pub t_gt: Matrix4<f64>,
    /// Ground-truth reference point (global-shape centroid) in the source's pre-centred frame,
    /// i.e. already minus the source's own mean.
    pub v_gt_source: [f32; 3],
    /// The same for the target, in the target's pre-centred frame.
    pub v_gt_target: [f32; 3],
}

fn mean(points: &[[f32; 3]]) -> [f64; 3] {
    let mut m = [0.0f64; 3];
    for p in points {
        for a in 0..3 {
            m[a] += p[a] as f64;
        }
    }
    m.map(|v| v / points.len().max(1) as f64)
}

impl Pair {
    /// The ground-truth shape centroid in the source's own frame (`v_gt_source` plus the
    /// source's mean, i.e. not pre-centred).
    pub fn source_centroid(&self) -> [f64; 3] {
        let m = mean(&self.source);
        [0, 1, 2].map(|a| m[a] + self.v_gt_source[a] as f64)
    }

    /// The same for the target, in the target's frame.
    pub fn target_centroid(&self) -> [f64; 3] {
        let m = mean(&self.target);
        [0, 1, 2].map(|a| m[a] + self.v_gt_target[a] as f64)
    }
}

impl From<&crate::data::Pair> for Pair {
    /// From the data pipeline's pair: the centroids are moved into each cloud's pre-centred
    /// frame (minus that cloud's own mean, as the network sees it).
    fn from(p: &crate::data::Pair) -> Self {
        let (ms, mt) = (mean(&p.source), mean(&p.target));
        Self {
            source: p.source.clone(),
            target: p.target.clone(),
            t_gt: p.T_target_source,
            v_gt_source: [0, 1, 2].map(|a| (p.centroid_source[a] - ms[a]) as f32),
            v_gt_target: [0, 1, 2].map(|a| (p.centroid_target[a] - mt[a]) as f32),
        }
    }
}
