//! Stage 1: the caller's [`Options`] checked and resolved.
//!
//! Takes the options and the model; gives [`Resolved`] (or an [`Error::InvalidOption`]). The
//! checks that need the clouds' scale (distances, voxel size) are [`distances`], called by
//! [`crate::pipeline::prepare`] once the normalisation is known.

use super::starts;
use crate::error::num;
use crate::grain::Grain;
use crate::model::Model;
use crate::refine;
use crate::register::{Options, MAX_NETWORK_POINTS};
use crate::{transform, Error, Result};
use nalgebra::Matrix4;

/// The size-based default final ICP distance in normalised units (2.5% of the clouds' shared
/// half-extent); a dense pair's default is less ([`default_distance`]).
const DEFAULT_MAX_CORRESPONDENCE: f64 = 0.025;

/// The cells [`crate::grain::of`] measures a cloud's grain in, normalised units: the size-based
/// default distance. In cells of half of it (the default ICP voxel) a noise of a tenth of the
/// cell lost its tails to the cell's faces (a 3-million-point bunny's noise read as a half to
/// 0.87 of what it was).
pub(crate) const GRAIN_CELL: f64 = DEFAULT_MAX_CORRESPONDENCE;

/// The coarser of two clouds' grains (either may be sparse: then the pair has none).
pub(crate) fn pair_grain(a: Option<Grain>, b: Option<Grain>) -> Option<Grain> {
    let (a, b) = (a?, b?);
    Some(Grain { spacing: a.spacing.max(b.spacing), spread: a.spread.max(b.spread) })
}

/// The default distance is at most this many of the pair's point spacings ([`Grain::spacing`]):
/// the size-based default spans 2.5-4 on objects' scans, the 3DMatch fragments and the paper's
/// pairs (which keep it), 7-9 on 500,000-point objects, 13-29 on a drone survey of 1-5 million
/// points and about 15 on a LiDAR frame, where an answer off by a fraction of it fits as well as
/// the right one (`BENCHMARK.md`, "Dense scenes: a default distance from the points' grain").
const GRAIN_SPACINGS: f64 = 6.0;

/// ...and no less than this many times its points' spread across their surface
/// ([`Grain::spread`]: noise) ...
const GRAIN_SPREADS: f64 = 3.0;

/// ...nor less than this share of the size-based default: ICP's voxels (half the distance) keep
/// at most about 16 times the points they keep at the default.
const MIN_GRAIN_SHARE: f64 = 0.25;

/// The default final distance for a pair whose grain is `grain` (normalised units; `None`: sparse
/// at the scale of [`GRAIN_CELL`]): [`DEFAULT_MAX_CORRESPONDENCE`], or [`GRAIN_SPACINGS`] of the
/// pair's spacing where that is less (within the bounds above), so that it shrinks smoothly as
/// the clouds get denser.
pub(crate) fn default_distance(grain: Option<Grain>) -> f64 {
    grain.map_or(DEFAULT_MAX_CORRESPONDENCE, |g| {
        (GRAIN_SPACINGS * g.spacing)
            .max(GRAIN_SPREADS * g.spread)
            .clamp(MIN_GRAIN_SHARE * DEFAULT_MAX_CORRESPONDENCE, DEFAULT_MAX_CORRESPONDENCE)
    })
}

/// The options that need no cloud to check, resolved.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Resolved {
    /// Points per cloud fed to the network.
    pub n_net: usize,
}

/// Checks the network size, the ICP iteration cap and the starts.
pub(crate) fn resolve(options: &Options, model: &Model) -> Result<Resolved> {
    let n_net = options.network_points.unwrap_or(model.config.n_points);
    if n_net < model.min_points() || n_net > MAX_NETWORK_POINTS {
        return Err(Error::InvalidOption(format!(
            "networkPoints = {n_net} is outside {}..={MAX_NETWORK_POINTS} for this model",
            model.min_points()
        )));
    }
    if options.icp_max_iterations > 10_000 {
        return Err(Error::InvalidOption(format!(
            "icpMaxIterations = {} is more than 10000",
            options.icp_max_iterations
        )));
    }
    // 0 would refine nothing yet judge the starts as if refined (`icp: "off"` says so)
    if options.icp_max_iterations == 0 {
        return Err(Error::InvalidOption(
            "icpMaxIterations = 0: each ICP stage needs at least 1 iteration (icp: \"off\" leaves ICP out)".into(),
        ));
    }
    refine::check_starts(&options.starts)?;
    // the starts that run with these options (`starts::kinds`: without the network,
    // "rotationsNetwork" is left out)
    if starts::kinds(options).is_empty() {
        return Err(Error::InvalidOption(
            "starts names only \"rotationsNetwork\", which needs the network (network: false): name \"rotations\" for the blind turns".into(),
        ));
    }
    if let Some(up) = options.up {
        // any length: only its direction counts (`Upright::of` scales it by its largest entry first)
        if !up.iter().all(|v| v.is_finite()) || nalgebra::Vector3::from(up).amax() == 0.0 {
            return Err(Error::InvalidOption(format!(
                "up = {up:?} must be three finite numbers, not all zero (the direction that is up in both clouds)"
            )));
        }
    }
    if let Some(share) = options.source_overlap {
        if !(share > 0.0 && share <= 1.0) {
            return Err(Error::InvalidOption(format!(
                "sourceOverlap = {} must be a number in (0, 1]: the share of the source that lies on the target once aligned \
                 (1 for a scan onto a complete model of it)",
                crate::error::num(share)
            )));
        }
    }
    source_scale(options)?;
    Ok(Resolved { n_net })
}

/// The options' `sourceScale` (1 when unset); an error unless it is a finite number > 0.
pub(crate) fn source_scale(options: &Options) -> Result<f64> {
    match options.source_scale {
        None => Ok(1.0),
        Some(f) if f.is_finite() && f > 0.0 => Ok(f),
        Some(f) => Err(Error::InvalidOption(format!(
            "sourceScale = {} must be a finite number > 0: the factor from the source's unit to the target's \
             (1000 for metres onto millimetres)",
            num(f)
        ))),
    }
}

/// The initial guess `T_target_source` in the caller's frame (identity when none is given), as
/// given (for the source scaled by `sourceScale`: its 3x3 part divided by it); an error when it is non-finite or not rigid to [`transform::RIGID_TOLERANCE`]. It is
/// made exactly rigid in the clouds' local frames ([`rigid_in_local_frames`]).
pub(crate) fn initial_transform(options: &Options) -> Result<Matrix4<f64>> {
    Ok(match &options.initial_transform {
        Some(rows) => {
            let mut m = transform::from_rows(rows);
            if m.iter().any(|v| !v.is_finite()) {
                return Err(Error::InvalidOption("initialTransform has a non-finite entry".into()));
            }
            // with `sourceScale` it maps the source as given: the rigid guess acts on the scaled source
            let scale = source_scale(options)?;
            if scale != 1.0 {
                m.fixed_view_mut::<3, 3>(0, 0).unscale_mut(scale);
            }
            transform::check_near_rigid(&m).map_err(|e| {
                // a rigid matrix given in the other order (a row-major list read column-major, or
                // the JSON's column-major list given to the CLI row by row)
                let transposed = transform::check_near_rigid(&m.transpose()).is_ok();
                let hint = if transposed {
                    ": its transpose is rigid, so its 16 numbers may be in the other order (JS and JSON: column-major, \
                     as three.js; the CLI's --initial-transform: row by row)"
                } else {
                    ""
                };
                let scaled = if scale != 1.0 {
                    format!(" once its 3x3 part is divided by sourceScale ({})", num(scale))
                } else {
                    String::new()
                };
                Error::InvalidOption(format!("initialTransform is not rigid{scaled}: {e}{hint}"))
            })?;
            m
        }
        None => Matrix4::identity(),
    })
}

/// The initial guess (checked by [`initial_transform`]) in the clouds' local frames, made exactly
/// rigid there ([`transform::nearest_rigid`]: the nearest rotation, the translation kept). Its
/// rotation is snapped about the source's origin, near its points: snapped in the caller's frame,
/// about a map grid's origin kilometres away, a guess written with a few decimals would move the
/// source by metres.
pub(crate) fn rigid_in_local_frames(
    init: &Matrix4<f64>,
    origin_source: [f64; 3],
    origin_target: [f64; 3],
) -> Result<Matrix4<f64>> {
    let local = crate::origin::to_local(init, origin_source, origin_target);
    transform::nearest_rigid(&local).map_err(|e| Error::InvalidOption(format!("initialTransform is not rigid: {e}")))
}

/// The least `maxCorrespondenceDistance`, as a share of f32's step at the clouds' half-extent
/// (`f32::EPSILON` of it): a ten-thousandth.
const MIN_DISTANCE_OF_F32_STEP: f64 = 1e-4;

/// The distance the answer's evidence and confidence are measured at, in normalised units: the
/// final ICP distance `d_final` the caller gave, or the size-based default when that is smaller
/// or the caller gave none. The confidence is calibrated at the size-based default; measured at a
/// wider distance the caller chose, every pose would fit better and a wrong one pass for right.
/// A dense pair's tighter default ([`default_distance`]) refines the answer, and its evidence is
/// still measured at the size-based default: at the tighter one a turned or slid look-alike of a
/// nearly round part fits less well and the probes stopped counting it (a casting's half views
/// 85 degrees off at 0.965 instead of 0.25: `BENCHMARK.md`, "Dense scenes: a default distance
/// from the points' grain").
pub(crate) fn evidence_distance(options: &Options, d_final: f64) -> f64 {
    match options.max_correspondence_distance {
        Some(_) => d_final.min(DEFAULT_MAX_CORRESPONDENCE),
        None => DEFAULT_MAX_CORRESPONDENCE,
    }
}

/// The distance the search's ICP stages start from ([`crate::refine::Refinement::d_coarse`]), in
/// normalised units: the final distance `d_final`, or the default one when that is larger. A
/// tight final distance sets how precisely the answer fits; the starts still travel as far as
/// at the default, then the stages halve down to it.
pub(crate) fn coarse_distance(d_final: f64) -> f64 {
    d_final.max(DEFAULT_MAX_CORRESPONDENCE)
}

/// The final ICP distance and the ICP voxel size in normalised units, for a normalisation of
/// scale `s` (user units per normalised unit) and a pair whose grain is `grain` (normalised
/// units; [`default_distance`] when the caller gives no distance).
pub(crate) fn distances(options: &Options, s: f64, grain: Option<Grain>) -> Result<(f64, f64)> {
    // beyond the clouds' largest half-extent (1 in normalised units) every point pairs with
    // one whatever the pose: a fit, and a confidence, that say nothing
    let too_far = |name: &str, v: f64, why: &str| {
        Error::InvalidOption(format!(
            "{name} = {} is more than the clouds' largest half-extent ({}): {why}",
            num(v),
            num(s),
        ))
    };
    let d_final = match options.max_correspondence_distance {
        Some(d) if d.is_finite() && d > 0.0 => {
            if d / s > 1.0 {
                return Err(too_far(
                    "maxCorrespondenceDistance",
                    d,
                    &format!(
                        "every point would pair with one, whatever the pose (the default distance is {} of it)",
                        DEFAULT_MAX_CORRESPONDENCE
                    ),
                ));
            }
            // far below f32's resolution at the clouds' size no pair can be within it, and the
            // halving schedule down to it from the default would not end (1e-310 trapped the
            // engine); a distance merely finer than that resolution is judged, with a warning
            if d / s < f64::from(f32::EPSILON) * MIN_DISTANCE_OF_F32_STEP {
                return Err(Error::InvalidOption(format!(
                    "maxCorrespondenceDistance = {} is less than a ten-thousandth of the step of the clouds' f32 \
                     coordinates at their size (half-extent {}: steps of about {}): no two points can be that \
                     near; give a few point spacings",
                    num(d),
                    num(s),
                    num(s * f64::from(f32::EPSILON))
                )));
            }
            d / s
        }
        Some(d) => {
            return Err(Error::InvalidOption(format!(
                "maxCorrespondenceDistance = {} must be a finite number > 0",
                num(d)
            )))
        }
        None => default_distance(grain),
    };
    let voxel = match options.voxel_size {
        // Voxels below a millionth of the clouds' half-extent cannot merge distinct f32 points
        // meaningfully (and would saturate the grid keys): treat them as "no voxelisation".
        Some(v) if v.is_finite() && v >= 0.0 => {
            if v / s > 1.0 {
                return Err(too_far(
                    "voxelSize",
                    v,
                    "a cloud would be a voxel or two, no shape left to align (the default is half the \
                     correspondence distance; 0 keeps every point)",
                ));
            }
            if v / s < 1e-6 {
                0.0
            } else {
                v / s
            }
        }
        Some(v) => {
            return Err(Error::InvalidOption(format!(
                "voxelSize = {} must be a finite number >= 0 (0: no voxelisation)",
                num(v)
            )))
        }
        // half the final distance; a wider one than the default keeps the default's voxels, on
        // which the answer's evidence is measured as it was calibrated (a dense pair's tighter
        // default takes finer ones: its answer is refined on them)
        None => d_final.min(DEFAULT_MAX_CORRESPONDENCE) * 0.5,
    };
    Ok((d_final, voxel))
}

#[cfg(test)]
mod tests {
    use super::*;

    const D: f64 = DEFAULT_MAX_CORRESPONDENCE;

    fn grain(spacing: f64, spread: f64) -> Option<Grain> {
        Some(Grain { spacing, spread })
    }

    #[test]
    fn a_dense_pairs_default_shrinks_smoothly_with_its_spacing_within_its_bounds() {
        // sparse at the cells' scale, or no denser than six spacings to the share: the share
        assert_eq!(default_distance(None), D);
        assert_eq!(default_distance(grain(D / 4.0, 0.0)), D);
        assert_eq!(default_distance(grain(D / 6.0, 0.0)), D);
        // denser: six spacings, continuous where it meets the share
        assert!((default_distance(grain(D / 6.0 * 0.999, 0.0)) - D * 0.999).abs() < 1e-12);
        assert!((default_distance(grain(D / 12.0, 0.0)) - D / 2.0).abs() < 1e-12);
        // no less than three spreads (noise) ...
        assert!((default_distance(grain(D / 12.0, D / 4.0)) - D * 0.75).abs() < 1e-12);
        // ... nor a quarter of the share
        assert_eq!(default_distance(grain(D / 100.0, 0.0)), D / 4.0);
        // the coarser of the two clouds
        let pair = pair_grain(grain(D / 12.0, 0.001), grain(D / 8.0, 0.0005)).unwrap();
        assert_eq!((pair.spacing, pair.spread), (D / 8.0, 0.001));
        assert!(pair_grain(grain(D / 12.0, 0.0), None).is_none());
    }

    #[test]
    fn the_evidence_is_measured_at_the_share_unless_the_caller_gives_a_tighter_distance() {
        let given = |d: f64| Options { max_correspondence_distance: Some(d), ..Options::default() };
        // a dense pair's own tighter default: evidence at the share, as calibrated
        assert_eq!(evidence_distance(&Options::default(), D / 3.0), D);
        // the caller's: the tighter of theirs and the share
        assert_eq!(evidence_distance(&given(1.0), D / 3.0), D / 3.0);
        assert_eq!(evidence_distance(&given(1.0), D * 3.0), D);
        // the voxel follows the final distance, up to the share's
        let (d, voxel) = distances(&Options::default(), 1.0, grain(D / 12.0, 0.0)).unwrap();
        assert!((d - D / 2.0).abs() < 1e-12 && (voxel - D / 4.0).abs() < 1e-12);
        let (d, voxel) = distances(&given(3.0 * D), 1.0, grain(D / 12.0, 0.0)).unwrap();
        assert!((d - 3.0 * D).abs() < 1e-12 && (voxel - D / 2.0).abs() < 1e-12);
    }
}
