//! Stage 2: the clouds prepared for the network and ICP.
//!
//! Takes the caller's clouds, the [`Options`] and [`Resolved`]; gives [`Prepared`]: the
//! validated clouds ([`checked`]: without their far outliers and their support plane) in their
//! local frames (f32 offsets from f64 origins), turned by the initial guess's rotation, jointly
//! normalised, sampled for the network and voxelised for ICP, with the initial guess and the ICP
//! distances in normalised units. The target's share is a [`PreparedTarget`] ([`super::target`]), taken over from the
//! previous call when it is the same target at the same scale (and resized for other options).
//! Warnings (collinear or flat clouds, unit mismatch, too few points for the network, far
//! outliers or a support plane left out) go to `warnings`.

use super::options::{self, Resolved};
use super::target::{self, InputKey, PreparedTarget, Sizes};
use super::upright::Upright;
use crate::cloud::{JointNormalization, PointCloud, MIN_POINTS};
use crate::error::num;
use crate::icp::IcpKind;
use crate::outliers::{self, Outliers};
use crate::register::Options;
use crate::spacing::Spacing;
use crate::support::{self, Support};
use crate::warning::{Warning, WarningCode};
use crate::{checks, limits, sampling, transform, Error, Result};
use nalgebra::{Matrix3, Matrix4, Vector3};
use std::borrow::Cow;

/// Ratio of the clouds' sizes (largest half-extents) above which a warning says they may be in
/// different units. A partial scan of an object is smaller than a model of the whole, but not by
/// this much; metres against millimetres is 1000.
const SIZE_RATIO_WARNING: f64 = 10.0;

/// The clouds and figures every later stage works on (normalised units unless named otherwise).
pub(crate) struct Prepared {
    /// The options' `sourceScale` (1 when unset): the source's points were multiplied by it.
    pub source_scale: f64,
    /// The source's f64 origin (caller's frame, scaled by `source_scale`).
    pub origin_source: [f64; 3],
    /// The initial guess's rotation, applied to the local source before normalising.
    pub rotate_init: Matrix4<f64>,
    /// The shared up axis in these frames (`Options::up`), if any.
    pub upright: Option<Upright>,
    /// The joint normalisation of the turned source and the target.
    pub norm: JointNormalization,
    /// The initial guess (identity with no initial transform), turned source to target.
    pub t_initial: Matrix4<f64>,
    /// The normalised, turned source.
    pub src_n: PointCloud,
    /// The ICP the search runs: the options', but point-to-point for point-to-plane on two flat
    /// clouds ([`checks::flat_pair`]).
    pub icp: IcpKind,
    /// The final ICP max correspondence distance.
    pub d_final: f64,
    /// The distance of the answer's evidence ([`options::evidence_distance`]).
    pub d_evidence: f64,
    /// The coarser of the steps the two clouds' `f32` coordinates were rounded to
    /// ([`checks::f32_rounding`]; 0 for clouds near zero), in normalised units.
    pub rounding: f64,
    /// The source points fed to the network.
    pub net_src: PointCloud,
    /// The voxelised source for ICP.
    pub icp_src: PointCloud,
    /// The target: normalised, sampled, voxelised (its origin in its summary).
    pub target: Box<PreparedTarget>,
}

impl Prepared {
    /// A point of the target's normalised frame in the caller's target frame (its origin and
    /// normalisation undone).
    pub(crate) fn in_target_frame(&self, q: Vector3<f64>) -> Vector3<f64> {
        let (o, centre, s) = (self.target.summary.origin, self.norm.target_center, self.norm.scale);
        Vector3::from(std::array::from_fn(|k| o[k] + centre[k] + q[k] * s))
    }
}

/// The target as [`prepare`] receives it: prepared by an earlier call from the same input, or
/// validated now.
enum Given<'a> {
    /// With the caller's target, which a kept target at another scale is prepared from again.
    Kept(Box<PreparedTarget>, Cow<'a, PointCloud>),
    Validated(PointCloud, Vec<Warning>, f64),
}

/// Validates, normalises and samples the pair (see the module docs); `kept` is a target prepared
/// by an earlier call, reused where it is the same target at the same scale.
pub(crate) fn prepare(
    source: Cow<'_, PointCloud>,
    target: Cow<'_, PointCloud>,
    options: &Options,
    resolved: &Resolved,
    kept: Option<Box<PreparedTarget>>,
    warnings: &mut Vec<Warning>,
) -> Result<Prepared> {
    let n_net = resolved.n_net;
    limits::check_cloud_points("source", source.len())?;
    limits::check_cloud_points("target", target.len())?;
    // the source in the target's unit (`sourceScale`): from here on the source as the pipeline sees it
    let source_scale = options::source_scale(options)?;
    let source = scaled(source, source_scale);
    let (source, mut source_warnings, source_spacing) = validated("source", source, options).map_err(|e| match e {
        Error::InvalidCloud(m) if source_scale != 1.0 => {
            Error::InvalidCloud(format!("{m} (its coordinates multiplied by sourceScale = {})", num(source_scale)))
        }
        e => e,
    })?;
    // the source's support plane, alone or as the pair of a cloud that stands on one
    // ([`support::Stands`]); the target's is searched for as such a pair where the source stands
    // on either
    let source_stands =
        source_spacing.as_ref().and_then(|s| support::Planes::of(&source.points, s)).and_then(|p| p.stands());
    let paired = source_stands.is_some();
    // the target given again: its checks passed already, and what it holds is reused below;
    // another target's is dropped before anything is allocated
    let input = InputKey::of(&target, options.non_finite, options.outliers, options.support_plane, paired);
    let kept = kept.filter(|k| k.input == input);
    let given = match kept {
        Some(k) => Given::Kept(k, target),
        None => {
            let (t, target_warnings, rounding) = checked("target", target, options, paired)?;
            Given::Validated(t, target_warnings, rounding)
        }
    };
    // a target that stands on a support plane: the source is its pair
    let target_warnings = match &given {
        Given::Kept(k, _) => &k.summary.warnings,
        Given::Validated(_, target_warnings, _) => target_warnings,
    };
    let target_stands = target_warnings.iter().any(|w| w.code == WarningCode::SupportPlaneDropped);
    let source_plane = source_stands.and_then(|s| s.plane(target_stands));
    let (source, source_rounding) = finished("source", source, source_plane, &mut source_warnings);
    warnings.extend(source_warnings);
    let spreads_source = checks::not_collinear("source", &source.points, warnings)?;
    let summary = match &given {
        Given::Kept(k, _) => k.summary.clone(),
        Given::Validated(t, target_warnings, rounding) => target::summary(t, target_warnings.clone(), *rounding)?,
    };
    warnings.extend(summary.warnings.iter().cloned());
    // on a flat pair a point-to-plane fit cannot move within the plane (every normal is its normal)
    let flat = checks::flat_pair(spreads_source, summary.spreads, options.icp != IcpKind::Off, warnings);
    let icp = if flat && options.icp == IcpKind::Plane { IcpKind::Point } else { options.icp };
    let init = options::initial_transform(options)?;
    // From here the pipeline works on each cloud's f32 offsets from its f64 origin (the local
    // frames); the caller's initial guess moves into them in f64: `Tr(-o_t) * init * Tr(o_s)`.
    // Its rotation is applied to the source's points, its translation kept in f64 (`shift`),
    // so a guess that moves the source far keeps the source's shape.
    let (origin_source, origin_target) = (source.origin, summary.origin);
    let source = source.into_local();
    let init_local = options::rigid_in_local_frames(&init, origin_source, origin_target)?;
    let rotate_init = transform::from_rotation_translation(&transform::rotation(&init_local), &Vector3::zeros());
    let shift = Matrix4::new_translation(&transform::translation(&init_local));
    let (size_source, size_target) = (source.half_extent(), summary.bounding.1);
    // how many times the larger of two sizes is the smaller
    let apart = |a: f64, b: f64| a.max(b) / a.min(b);
    let size_ratio = apart(size_source, size_target);
    if size_ratio > SIZE_RATIO_WARNING {
        // a factor given the wrong way round: its inverse would make the sizes agree
        let inverse = size_source / (source_scale * source_scale);
        let reversed = source_scale != 1.0 && apart(inverse, size_target) <= SIZE_RATIO_WARNING;
        let hint = if reversed {
            format!(
                "; sourceScale = {} may be the wrong way round: its inverse, {}, makes the sizes agree",
                num(source_scale),
                num(1.0 / source_scale)
            )
        } else {
            String::new()
        };
        warnings.push(Warning::new(WarningCode::SizeMismatch, format!(
            "the clouds differ in size by {}x (largest half-extents: source {}, target {}): registration is rigid, so both must be in the same unit (e.g. both metres, not metres and millimetres); if they are not, multiply one cloud's coordinates by the factor between the units (1000 from metres to millimetres: the option sourceScale does it for the source){hint}",
            num(size_ratio.round()),
            num(size_source),
            num(size_target)
        )));
    }
    // The network sees the source already turned by the initial guess (its shift only moves
    // the source's centre, which the normalisation removes).
    let source_init = if transform::rotation(&init_local) == Matrix3::identity() {
        source
    } else {
        source.into_transformed(&rotate_init)
    };
    let norm = JointNormalization::of_boxes(JointNormalization::box_of(&source_init), summary.bounding);
    // the initial guess (identity with no initialTransform), from the turned source to the target
    let t_initial = norm.normalize_transform(&shift);
    checks::initial_distance(&t_initial)?;
    let src_n = source_init.into_transformed(&norm.source_to_normalized());
    // how finely the pair resolves its surfaces, for the default distance (a distance the caller
    // gives needs none: the source's pass is skipped): the coarser of the two, normalised units
    let grain = match options.max_correspondence_distance {
        Some(_) => None,
        None => options::pair_grain(
            crate::grain::of(&src_n.points, options::GRAIN_CELL),
            summary.grain.map(|g| g.scaled(1.0 / norm.scale)),
        ),
    };
    let (d_final, voxel) = options::distances(options, norm.scale, grain)?;
    let sizes = Sizes { scale: norm.scale.to_bits(), voxel: voxel.to_bits(), n_net, seed: options.seed };
    let target = match given {
        Given::Kept(mut k, _) if k.sizes.scale == sizes.scale => {
            k.resize(sizes);
            k
        }
        // the same target at another scale (a source larger than it)
        Given::Kept(old, target) => {
            drop(old);
            let local = checked("target", target, options, paired)?.0.into_local();
            Box::new(PreparedTarget::new(input, summary, sizes, local, &norm))
        }
        Given::Validated(t, _, _) => Box::new(PreparedTarget::new(input, summary, sizes, t.into_local(), &norm)),
    };
    for (what, len) in [("source", src_n.len()), ("target", target.cloud.len())] {
        if len < n_net {
            warnings.push(Warning::new(
                WarningCode::NetworkResampled,
                format!(
                "{what} has {len} points, fewer than the {n_net} the network takes: it saw some of them twice (the \
                 network's estimate is only a start; the answer is refined on every point)"
            ),
            ));
        }
    }
    let net_src = sampling::network_sample(&src_n, n_net, options.seed);
    let icp_src = sampling::voxel_downsample(&src_n, voxel as f32);
    // what ICP keeps must fit next to the inputs before its k-d trees and normals are built
    let voxel_user = voxel * norm.scale;
    let default = options.voxel_size.is_none();
    limits::check_icp_points("source", src_n.len(), icp_src.len(), voxel_user, default)?;
    limits::check_icp_points("target", target.cloud.len(), target.icp.len(), voxel_user, default)?;
    let upright = Upright::of(options, &rotate_init);
    let d_evidence = options::evidence_distance(options, d_final);
    let rounding = source_rounding.max(target.summary.rounding) / norm.scale;
    Ok(Prepared {
        source_scale,
        origin_source,
        rotate_init,
        upright,
        norm,
        t_initial,
        src_n,
        icp,
        d_final,
        d_evidence,
        rounding,
        net_src,
        icp_src,
        target,
    })
}

/// `cloud` with its coordinates (origin and offsets) multiplied by `factor`; as it is for 1.
fn scaled(cloud: Cow<'_, PointCloud>, factor: f64) -> Cow<'_, PointCloud> {
    if factor == 1.0 {
        return cloud;
    }
    Cow::Owned(cloud.into_owned().into_transformed(&Matrix4::new_nonuniform_scaling(&Vector3::repeat(factor))))
}

/// Points exactly at (0, 0, 0) from which a cloud is warned about: more than one is no
/// coincidence.
const MIN_AT_ZERO: usize = 2;

/// `cloud` validated ([`PointCloud::validated`], `options.non_finite`); with [`Outliers::Drop`]
/// without its far outliers ([`outliers::drop_far_with`]), with a warning for each that left
/// points out; and, with [`Support::Drop`], the sample its support plane is searched in.
/// `what` names the cloud in messages.
fn validated(
    what: &str,
    cloud: Cow<'_, PointCloud>,
    options: &Options,
) -> Result<(PointCloud, Vec<Warning>, Option<Spacing>)> {
    let given = cloud.len();
    let mut cloud = cloud.into_owned().into_validated(what, MIN_POINTS, options.non_finite)?;
    let mut warnings = Vec::new();
    if cloud.len() < given {
        warnings.push(Warning::new(
            WarningCode::NonFiniteDropped,
            format!(
                "left out {} of the {what}'s {given} points: a non-finite coordinate (NaN, infinite) or one beyond \
                 1e18 (`nonFinite: \"drop\"`)",
                given - cloud.len()
            ),
        ));
    }
    // the two tests' sample, shared while the cloud is unchanged
    let mut spacing = None;
    if options.outliers == Outliers::Drop {
        let (sampled, total) = (Spacing::of(&cloud.points), cloud.len());
        let (kept, dropped) = outliers::drop_far_with(cloud, &sampled);
        cloud = kept;
        if dropped == 0 {
            spacing = Some(sampled);
        } else {
            warnings.push(Warning::new(WarningCode::OutliersDropped, outliers::warning(what, dropped, total)));
        }
    }
    let spacing = match options.support_plane {
        Support::Drop => Some(spacing.unwrap_or_else(|| Spacing::of(&cloud.points))),
        Support::Keep => None,
    };
    Ok((cloud, warnings, spacing))
}

/// `cloud` [`validated`], then without its support plane ([`support::Planes::alone`], or else
/// [`support::Planes::paired`] where `paired`: the other cloud stands on one by either) with
/// [`Support::Drop`]; see [`finished`].
fn checked(
    what: &str,
    cloud: Cow<'_, PointCloud>,
    options: &Options,
    paired: bool,
) -> Result<(PointCloud, Vec<Warning>, f64)> {
    let (cloud, mut warnings, spacing) = validated(what, cloud, options)?;
    let plane = spacing
        .as_ref()
        .and_then(|s| support::Planes::of(&cloud.points, s))
        .and_then(|p| p.alone().or_else(|| paired.then(|| p.paired()).flatten()));
    let (cloud, rounding) = finished(what, cloud, plane, &mut warnings);
    Ok((cloud, warnings, rounding))
}

/// A [`validated`] `cloud` without its support `plane`, if any, and the step the `f32`
/// coordinates of the points kept are rounded to ([`checks::f32_rounding`], its units); a warning
/// for the plane, for points at (0, 0, 0) and for a coarse rounding goes to `warnings`.
fn finished(
    what: &str,
    mut cloud: PointCloud,
    plane: Option<support::SupportPlane>,
    warnings: &mut Vec<Warning>,
) -> (PointCloud, f64) {
    if let Some(plane) = plane {
        warnings.push(Warning::new(
            WarningCode::SupportPlaneDropped,
            support::warning(what, plane.indices.len(), cloud.len()),
        ));
        cloud = cloud.without(&plane.indices);
    }
    // a depth camera's pixels without a return, written as (0, 0, 0): a cluster the outlier test
    // may keep (it is dense), which stretches the clouds' box and so the default distance
    let at_zero = (0..cloud.len()).filter(|&i| cloud.point_f64(i) == [0.0; 3]).count();
    if at_zero >= MIN_AT_ZERO {
        warnings.push(Warning::new(
            WarningCode::PointsAtZero,
            format!(
                "{at_zero} of the {what}'s points lie exactly at (0, 0, 0), as a depth camera writes its pixels \
                 without a return: remove them (they are registered as points, and they widen the clouds' box and \
                 the default distance)"
            ),
        ));
    }
    // the points kept (a stray left out, far from zero, rounds nothing that is registered)
    let rounding = checks::f32_rounding(what, &cloud, warnings);
    (cloud, rounding)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `n` points on a twisted, asymmetric surface patch of about `size` across.
    fn patch(n: usize, size: f32, phase: f32) -> PointCloud {
        let points = (0..n)
            .map(|i| {
                let (u, v) = ((i % 97) as f32 / 96.0, (i / 97) as f32 / (n / 97) as f32);
                [u * size, v * size * 0.7, (3.0 * u + phase).sin() * (2.0 * v).cos() * size * 0.2]
            })
            .collect();
        PointCloud::new(points)
    }

    #[test]
    fn a_target_given_again_is_reused_for_smaller_sources_as_far_as_the_options_allow() {
        let target = patch(9_700, 2.0, 0.0);
        let resolved = Resolved { n_net: 128 };
        let options = Options::default();
        let prepare_onto = |source: &PointCloud, target: &PointCloud, options: &Options, kept| {
            prepare(Cow::Borrowed(source), Cow::Borrowed(target), options, &resolved, kept, &mut Vec::new())
                .unwrap()
                .target
        };
        let first = prepare_onto(&patch(2_000, 1.0, 0.5), &target, &options, None);
        first.index();
        // another source smaller than the target: the target is kept (its index built)
        let second = prepare_onto(&patch(3_000, 1.2, 1.0), &target, &options, Some(first));
        assert!(second.is_indexed());
        // another seed: the same ICP cloud and index, another network sample
        let seeded = Options { seed: 9, ..Options::default() };
        let net = second.net.points.clone();
        let third = prepare_onto(&patch(3_000, 1.2, 1.0), &target, &seeded, Some(second));
        assert!(third.is_indexed());
        assert_ne!(third.net.points, net);
        // another voxel: ICP's cloud and index made anew
        let voxel = Options { voxel_size: Some(0.05), ..Options::default() };
        let icp = third.icp.len();
        let fourth = prepare_onto(&patch(3_000, 1.2, 1.0), &target, &voxel, Some(third));
        assert!(!fourth.is_indexed());
        assert_ne!(fourth.icp.len(), icp);
        fourth.index();
        // a source larger than the target (another scale): all anew
        let fifth = prepare_onto(&patch(4_000, 5.0, 2.0), &target, &options, Some(fourth));
        assert!(!fifth.is_indexed());
        // the same points at another origin: another target
        let sixth = prepare_onto(&patch(3_000, 1.2, 1.0), &target, &options, None);
        sixth.index();
        let moved = PointCloud::with_origin(target.points.clone(), [10.0, 0.0, 0.0]);
        assert!(!prepare_onto(&patch(3_000, 1.2, 1.0), &moved, &options, Some(sixth)).is_indexed());
    }
}
