//! Stage 2, the target's share: the target validated, in its local frame, normalised, sampled for
//! the network and voxelised for ICP, with its k-d tree, normals and global descriptors made as
//! they are first needed ([`PreparedTarget`]).
//!
//! A [`crate::Registrar`] keeps the last target it prepared. A registration onto the same target
//! (the same points, origin and `nonFinite` option, recognised by [`InputKey`]'s fingerprint)
//! reuses what depends on the target alone ([`TargetSummary`]: the validation, its box and
//! spreads). When the normalisation's scale is the same too (a source no larger than the target),
//! it reuses the normalised target with its centroid and the descriptors found so far, and, as
//! far as the options leave them unchanged ([`Sizes`]), ICP's voxelised copy with its index and
//! normals (the same ICP voxel) and the network's sample (the same point count and seed). Each
//! piece is what preparing anew would make, so the result is the same either way.

use crate::cloud::{JointNormalization, NonFinite, PointCloud};
use crate::global::{self, TargetFeatures};
use crate::grain::{self, Grain};
use crate::icp::IcpTarget;
use crate::outliers::Outliers;
use crate::support::Support;
use crate::warning::Warning;
use crate::{checks, limits, sampling, Result};
use std::sync::OnceLock;

/// What recognises a target given again: a 128-bit fingerprint (XXH3) of its points' bytes, their
/// count, its origin, the `nonFinite`, `outliers` and `supportPlane` options and whether its
/// support plane was searched for as the pair of a source that stands on one (by either share,
/// [`crate::support::find_paired`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct InputKey {
    fingerprint: u128,
    len: usize,
    origin: [u64; 3],
    non_finite: NonFinite,
    outliers: Outliers,
    support: Support,
    paired: bool,
}

impl InputKey {
    /// The key of `cloud` checked with `non_finite`, `outliers` and `support`, `paired` with a
    /// source that stands on a support plane (one pass over its points).
    pub(crate) fn of(
        cloud: &PointCloud,
        non_finite: NonFinite,
        outliers: Outliers,
        support: Support,
        paired: bool,
    ) -> Self {
        let mut hasher = xxhash_rust::xxh3::Xxh3::new();
        // the points' little-endian bytes, a chunk at a time
        let mut buf = [0u8; 12 * 256];
        for chunk in cloud.points.chunks(256) {
            for (p, out) in chunk.iter().zip(buf.chunks_exact_mut(12)) {
                for (v, o) in p.iter().zip(out.chunks_exact_mut(4)) {
                    o.copy_from_slice(&v.to_le_bytes());
                }
            }
            hasher.update(&buf[..12 * chunk.len()]);
        }
        Self {
            fingerprint: hasher.digest128(),
            len: cloud.len(),
            origin: cloud.origin.map(f64::to_bits),
            non_finite,
            outliers,
            support,
            paired,
        }
    }
}

/// What the pipeline needs of the target before the normalisation, from its validated points in
/// their local frame.
#[derive(Clone, Debug)]
pub(crate) struct TargetSummary {
    /// The target's f64 origin (caller's frame).
    pub origin: [f64; 3],
    /// Its bounding box's centre and largest half-extent (local frame; see
    /// [`JointNormalization::box_of`]).
    pub bounding: ([f64; 3], f64),
    /// Its principal spreads ([`checks::not_collinear`]).
    pub spreads: [f64; 3],
    /// The warnings its checks gave (points left out, a nearly collinear target).
    pub warnings: Vec<Warning>,
    /// The step its `f32` coordinates are rounded to (`checks::f32_rounding`, its units).
    pub rounding: f64,
    /// How finely it resolves its surface ([`grain::of`] in cells of the default distance at its
    /// own size; its units), `None` when sparse at that scale.
    pub grain: Option<Grain>,
}

/// What the prepared target depends on besides the target: the normalisation's scale (the
/// normalised cloud, its centroid and descriptors), the ICP voxel (normalised units: ICP's cloud
/// and index), the network's point count and the seed (its sample); as bits, for exact equality.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Sizes {
    pub scale: u64,
    pub voxel: u64,
    pub n_net: usize,
    pub seed: u64,
}

/// The network's sample of the normalised target `cloud` (its seed: the options' seed `^`
/// [`sampling::TARGET_SEED_XOR`]).
fn net_sample(cloud: &PointCloud, sizes: &Sizes) -> PointCloud {
    sampling::network_sample(cloud, sizes.n_net, sizes.seed ^ sampling::TARGET_SEED_XOR)
}

/// ICP's copy of the normalised target `cloud`: voxelised at `sizes.voxel`.
fn icp_cloud(cloud: &PointCloud, sizes: &Sizes) -> PointCloud {
    sampling::voxel_downsample(cloud, f64::from_bits(sizes.voxel) as f32)
}

/// The summary of the validated `target` (its origin not yet dropped); an error when it is
/// collinear. `warnings`: what its checks said (`prepare::checked`), kept among its warnings.
pub(crate) fn summary(target: &PointCloud, warnings: Vec<Warning>, rounding: f64) -> Result<TargetSummary> {
    let mut warnings = warnings;
    let spreads = checks::not_collinear("target", &target.points, &mut warnings)?;
    let bounding = JointNormalization::box_of(target);
    let grain = grain::of(&target.points, super::options::GRAIN_CELL * bounding.1);
    Ok(TargetSummary { origin: target.origin, bounding, spreads, warnings, rounding, grain })
}

/// The target prepared for the network, ICP and the global hypotheses (normalised units), with
/// what identifies it.
#[derive(Debug)]
pub(crate) struct PreparedTarget {
    /// The input it was made from.
    pub input: InputKey,
    /// What the pipeline needs of it before the normalisation.
    pub summary: TargetSummary,
    /// What its normalised clouds depend on besides the target.
    pub sizes: Sizes,
    /// The normalised target.
    pub cloud: PointCloud,
    /// The points fed to the network.
    pub net: PointCloud,
    /// The voxelised target for ICP.
    pub icp: PointCloud,
    /// ICP's k-d tree of [`PreparedTarget::icp`] and its normals, built on first use (after
    /// the memory limits are checked).
    index: OnceLock<IcpTarget>,
    /// The centroid of [`PreparedTarget::cloud`], computed on first use.
    centroid: OnceLock<[f64; 3]>,
    /// Its side of the global hypotheses, filled as they need it.
    pub features: TargetFeatures,
}

impl PreparedTarget {
    /// Normalises the `local` target by `norm` (whose scale `sizes.scale` is), samples
    /// `sizes.n_net` points of it for the network and voxelises it for ICP.
    pub(crate) fn new(
        input: InputKey,
        summary: TargetSummary,
        sizes: Sizes,
        local: PointCloud,
        norm: &JointNormalization,
    ) -> Self {
        let cloud = local.into_transformed(&norm.target_to_normalized());
        let net = net_sample(&cloud, &sizes);
        let icp = icp_cloud(&cloud, &sizes);
        Self {
            input,
            summary,
            sizes,
            cloud,
            net,
            icp,
            index: OnceLock::new(),
            centroid: OnceLock::new(),
            features: TargetFeatures::default(),
        }
    }

    /// Brings the kept target to `sizes`, whose scale is its own: voxelised again for ICP (its
    /// index and normals dropped, and its descriptors when ICP's copy may stand in for it,
    /// `global::standin`) when the voxel differs, sampled again for the network when the point
    /// count or the seed does; the normalised cloud and its centroid stay.
    pub(crate) fn resize(&mut self, sizes: Sizes) {
        debug_assert_eq!(self.sizes.scale, sizes.scale);
        if self.sizes.voxel != sizes.voxel {
            let was = self.icp.len();
            self.icp = icp_cloud(&self.cloud, &sizes);
            self.index = OnceLock::new();
            // the descriptors were made from ICP's copy where it could stand in for the target
            // (`global::standin`)
            if [was, self.icp.len()].iter().any(|&n| global::saves_enough(self.cloud.len(), n)) {
                self.features = TargetFeatures::default();
            }
        }
        if (self.sizes.n_net, self.sizes.seed) != (sizes.n_net, sizes.seed) {
            self.net = net_sample(&self.cloud, &sizes);
        }
        self.sizes = sizes;
    }

    /// ICP's index of the voxelised target (normals estimated as ICP first needs them; a large
    /// target with coarser copies for the wide stages, [`IcpTarget::with_levels`], where they fit
    /// the memory budget, [`limits::icp_copies_fit`]).
    pub(crate) fn index(&self) -> &IcpTarget {
        self.index.get_or_init(|| {
            if limits::icp_copies_fit(self.cloud.len(), self.icp.len()) {
                IcpTarget::with_levels(&self.icp.points, f64::from_bits(self.sizes.voxel))
            } else {
                IcpTarget::new(&self.icp.points, false)
            }
        })
    }

    /// Whether ICP's index was built (by this call or an earlier one).
    #[cfg(test)]
    pub(crate) fn is_indexed(&self) -> bool {
        self.index.get().is_some()
    }

    /// The normalised target's centroid.
    pub(crate) fn centroid(&self) -> [f64; 3] {
        *self.centroid.get_or_init(|| self.cloud.centroid())
    }
}
