//! Training pairs: stream index -> protocol pair ([`crate::data::source::ShapeSource`], train split
//! only) -> the engine's frames ([`crate::data::Pair::engine_frames`]) -> the engine's network
//! sample ([`crate::data::EnginePair::network_sample`]) -> a [`crate::train::Pair`] with `v_gt_*`
//! pre-centred on the sampled points' means (the network pre-centres its input the same way).

use super::{Curriculum, RunConfig};
use crate::data::source::{ShapeSource, Split};
use crate::data::{mix, unit_of_hash, PairParams};
use crate::train::Pair as TrainPair;
use crate::Result;

/// The data side of a run.
pub struct TrainData {
    /// Shapes (procedural + bank), split by shape.
    pub source: ShapeSource,
    /// The full protocol (validation; the curriculum's end point).
    pub full: PairParams,
    /// The curriculum.
    pub curriculum: Curriculum,
    /// Network points per cloud.
    pub n: usize,
    /// [`RunConfig::pose_angle_deg`] (training pairs only).
    pub pose_angle_deg: f64,
    /// [`RunConfig::part_whole`] (training pairs only).
    pub part_whole: f64,
    /// Stream offset derived from the seed.
    pub stream: u64,
    /// Bank summary for the log: (usable meshes, skipped, train meshes, val meshes).
    pub bank_counts: (usize, usize, usize, usize),
}

impl TrainData {
    /// Builds the shape source (loading the bank, if any) for a run.
    pub fn new(cfg: &RunConfig) -> std::result::Result<Self, String> {
        let (mut source, counts) = match &cfg.bank {
            Some(dir) => {
                let b = super::bank_pack::load(std::path::Path::new(dir)).map_err(|e| format!("bank {dir}: {e}"))?;
                let (usable, skipped) = (b.meshes.len(), b.skipped.len());
                let s = ShapeSource::with_bank(b, cfg.val_fraction);
                let c = (usable, skipped, s.bank_train.len(), s.bank_val.len());
                (s, c)
            }
            None => (ShapeSource::procedural(), (0, 0, 0, 0)),
        };
        source.bank_fraction = cfg.bank_fraction;
        let full = PairParams { points: cfg.pair_points, ..PairParams::default() };
        Ok(Self {
            source,
            full,
            curriculum: cfg.curriculum.clone(),
            n: cfg.model.n_points,
            pose_angle_deg: cfg.pose_angle_deg,
            part_whole: cfg.part_whole,
            stream: cfg.seed.wrapping_mul(1 << 40),
            bank_counts: counts,
        })
    }

    /// Training pair number `i` of the stream (deterministic in `(seed, i)`).
    pub fn train_pair(&self, i: u64) -> Result<TrainPair> {
        let (p, sample_seed) = self.train_protocol_pair(i)?;
        Ok(to_train_pair(&p, self.n, sample_seed))
    }

    /// Training pair number `i` in the pair's own units, with the seed of its network sample
    /// ([`Self::train_pair`] is `to_train_pair` of these).
    pub fn train_protocol_pair(&self, i: u64) -> Result<(crate::data::Pair, u64)> {
        let mut params = PairParams { pose_angle_deg: self.pose_angle_deg, ..self.curriculum.params(i, &self.full) };
        let index = self.stream.wrapping_add(i);
        if let Some(keep) = part_of_whole(index, self.part_whole) {
            params.keep_ratio = keep;
            params.target_keep_ratio = Some(1.0);
        }
        let p = self.source.pair(Split::Train, index, &params)?;
        Ok((p, mix(index, 0x11E7)))
    }

    /// Validation pair `i` (full protocol; the same pair as `arps make-pairs --split val --seed 0`
    /// writes as number `i`, given the same bank and fractions).
    pub fn val_pair(&self, i: u64) -> Result<crate::data::Pair> {
        self.source.pair(Split::Val, i, &self.full)
    }
}

/// The range of the source's crop in a part-against-whole training pair ([`RunConfig::part_whole`]).
pub const PART_KEEP: (f64, f64) = (0.3, 0.6);

/// When pair `index` of the stream is a part against the whole (with probability `share`), the
/// fraction of the shape its source's crop keeps (in [`PART_KEEP`]).
pub fn part_of_whole(index: u64, share: f64) -> Option<f64> {
    (share > 0.0 && unit_of_hash(mix(index, 0x9A27_0001)) < share)
        .then(|| PART_KEEP.0 + (PART_KEEP.1 - PART_KEEP.0) * unit_of_hash(mix(index, 0x9A27_0002)))
}

/// A protocol pair as the network sees it: engine frames, `n` network points per cloud drawn with
/// the engine's rule for `Options::seed = sample_seed`, centroids pre-centred on the samples' means.
pub fn to_train_pair(p: &crate::data::Pair, n: usize, sample_seed: u64) -> TrainPair {
    let ep = p.engine_frames();
    let (s, t) = ep.network_sample(n, sample_seed);
    let (ms, mt) = (s.centroid(), t.centroid());
    let pre = |c: [f64; 3], m: [f64; 3]| [0, 1, 2].map(|a| (c[a] - m[a]) as f32);
    TrainPair {
        v_gt_source: pre(ep.centroid_source, ms),
        v_gt_target: pre(ep.centroid_target, mt),
        source: s.points,
        target: t.points,
        t_gt: ep.T_target_source,
    }
}
