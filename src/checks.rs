//! Checks on what the pipeline computes: results that are not finite, initial guesses that
//! leave no overlap to find.

use crate::warning::{Warning, WarningCode};
use crate::{Error, Result};
use nalgebra::Matrix4;

/// The farthest, in normalised units (the clouds' shared half-extent), the initial guess (the
/// caller's `initialTransform`, or the identity in the caller's frame) may put the source's
/// centre from the target's. The network's start does not depend on it, but the starts from the
/// initial guess are refined in `f32`, where squared distances beyond about 1e19 overflow; this
/// bound keeps them finite with a wide margin, while clouds given in different frames (one in
/// map-grid coordinates, one near zero) still register.
pub const MAX_INITIAL_DISTANCE: f64 = 1.0e12;

/// Fails when any entry of `t` (a `T_target_source`) is NaN or infinite; `what` names it.
pub fn finite_transform(t: &Matrix4<f64>, what: &str) -> Result<()> {
    if t.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(Error::Numerical(format!(
            "{what} is not finite (a NaN or infinite entry): the inputs are out of the range the engine can compute with"
        )))
    }
}

/// Fails when the initial guess `t_initial_n` (normalised units) moves the source's centre more
/// than [`MAX_INITIAL_DISTANCE`] from the target's.
pub fn initial_distance(t_initial_n: &Matrix4<f64>) -> Result<()> {
    let d = t_initial_n.fixed_view::<3, 1>(0, 3).norm();
    if d.is_finite() && d <= MAX_INITIAL_DISTANCE {
        Ok(())
    } else {
        let far = if d.is_finite() {
            format!("{} cloud sizes", crate::error::num(d))
        } else {
            "at a non-finite distance".into()
        };
        Err(Error::InvalidOption(format!(
            "the initial guess (initialTransform, or the identity in the caller's frame) puts the source {far} away from the target, more than the {MAX_INITIAL_DISTANCE:e} cloud sizes the engine computes with: give an initialTransform that brings the clouds near each other"
        )))
    }
}

/// The spacing of `f32` values at a cloud's farthest coordinate, as a fraction of its largest
/// half-extent, beyond which the cloud gets a warning ([`f32_rounding`]): its points were
/// rounded to a grid coarser than 1% of the default correspondence distance (0.025 of the
/// half-extent) before the engine saw them. (A 2 m car 1 km from zero is not warned; a 100 m
/// scan on a map grid, 4e6 from zero, rounded to 0.25-0.5, is.)
pub const F32_ROUNDING_WARNING: f64 = 2.5e-4;

/// True when `f32` holds coordinates up to `far` from zero only to a step of more than
/// [`F32_ROUNDING_WARNING`] of a cloud's half-extent `half` (the rule of [`f32_rounding`] and of
/// [`crate::PointCloud::placed`]); false for a non-finite `far`.
pub fn f32_rounds(far: f64, half: f64) -> bool {
    far.is_finite() && f32_step(far) > F32_ROUNDING_WARNING * half
}

/// The spacing of `f32` values at `far` from zero (the gap between two neighbours there: 0.5 at
/// 5.4e6); 0 at zero, and not finite for a non-finite `far`.
pub fn f32_step(far: f64) -> f64 {
    let far = far.abs();
    if !far.is_finite() {
        return f64::INFINITY;
    }
    if far == 0.0 {
        return 0.0;
    }
    // 2^(e - 23) for `far` in [2^e, 2^(e+1)), from the f64's exponent bits (no libm); below
    // f32's smallest normal its spacing is fixed (a subnormal f64 reads as e = -1023)
    let e = ((far.to_bits() >> 52) & 0x7ff) as i64 - 1023;
    f64::from_bits(((e.max(-126) - 23 + 1023) as u64) << 52)
}

/// Warns (into `warnings`; `what` names the cloud) when the cloud's points sit on a grid coarser
/// than [`F32_ROUNDING_WARNING`] of its largest half-extent because they were `f32` values far
/// from zero: a cloud given as `f32` far from zero (a map grid; `PointCloud::new`, a
/// `Float32Array`), or read from a file that stores them as 32-bit floats ([`stored_f32_step`]:
/// the reader's `f64` offsets from a nearby origin keep that grid). Either has lost those digits
/// already, and the answer can be as coarse. Returns that step (the spacing of `f32` values at
/// the cloud's farthest coordinate, in its units; 0 for a cloud at zero, or one stored as offsets
/// whose points are not on such a grid), warned or not.
pub fn f32_rounding(what: &str, cloud: &crate::PointCloud, warnings: &mut Vec<Warning>) -> f64 {
    let (lo, hi) = cloud.bounds();
    let half = crate::cloud::half_extent_of(lo, hi);
    if !cloud.origin_is_zero() {
        let (step, far) = stored_step(cloud, lo, hi);
        if half > 0.0 && step > F32_ROUNDING_WARNING * half {
            warnings.push(Warning::new(
                WarningCode::CoarseCoordinates,
                format!(
                "the {what}'s coordinates lie up to {} from zero for a cloud of largest half-extent {}, on the grid \
                 of 32-bit floats there (a file that stores them as float?): they were rounded to steps of about {} \
                 before they were read (unless that is a grid of their own, such as a terrain model posted at that \
                 step), and the answer can be as coarse; store them as double, or as offsets from a nearby origin",
                crate::error::num(far),
                crate::error::num(half),
                crate::error::num(step)
            ),
            ));
        }
        return step;
    }
    let far = lo.iter().chain(&hi).fold(0.0f64, |m, v| m.max((*v as f64).abs()));
    let step = f32_step(far);
    if half > 0.0 && f32_rounds(far, half) {
        warnings.push(Warning::new(
            WarningCode::CoarseCoordinates,
            format!(
                "the {what}'s coordinates lie up to {} from zero for a cloud of largest half-extent {}: as f32 they \
                 are rounded to steps of about {}, and the answer can be as coarse; pass them as f64 (a Float64Array, \
                 readPointCloud's {{ points, origin }}, PointCloud::from_points_f64)",
                crate::error::num(far),
                crate::error::num(half),
                crate::error::num(step)
            ),
        ));
    }
    step
}

/// Points of a cloud [`stored_f32_step`] looks at, evenly spread.
pub const STORED_F32_SAMPLE: usize = 256;

/// For a cloud stored as `f32` offsets from an `f64` origin: the step of the `f32` grid its points
/// sit on in the caller's frame, and how far from zero its farthest coordinate lies. A file that
/// stores coordinates far from zero as 32-bit floats (a PLY `float`, a PCD `F 4`) gives values
/// on that grid (0.5 apart at 5.4e6), which the reader's offsets keep to within their own `f32`
/// rounding; `f64` values are on it only by chance (one coordinate in a few thousand at 5.4e6).
/// Per axis, when every one of [`STORED_F32_SAMPLE`] points evenly spread has its coordinate on
/// the grid (within the offsets' rounding, and that grid at least 8 times as coarse), and not all
/// of them on twice the grid (a posting of the data's own, such as a terrain model's), that axis's
/// step counts; the largest counts. `(0, far)` when no axis is on such a grid.
pub fn stored_f32_step(cloud: &crate::PointCloud) -> (f64, f64) {
    let (lo, hi) = cloud.bounds();
    stored_step(cloud, lo, hi)
}

/// [`stored_f32_step`] of a cloud whose offsets' bounds are `[lo, hi]` (taken once by the caller).
fn stored_step(cloud: &crate::PointCloud, lo: [f32; 3], hi: [f32; 3]) -> (f64, f64) {
    let n = cloud.points.len();
    let mut far = 0.0f64;
    let mut step = 0.0f64;
    for a in 0..3 {
        let (l, h) = (cloud.origin[a] + lo[a] as f64, cloud.origin[a] + hi[a] as f64);
        let far_a = l.abs().max(h.abs());
        far = far.max(far_a);
        // how far the offsets' own f32 rounding may move a value; the grid must be much coarser
        let slack = f32_step((lo[a] as f64).abs().max((hi[a] as f64).abs()));
        let grid = f32_step(far_a);
        if n == 0 || !far_a.is_finite() || grid < 8.0 * slack {
            continue;
        }
        let value = |i: usize| cloud.origin[a] + cloud.points[i][a] as f64;
        let sample = (0..n).step_by(n.div_ceil(STORED_F32_SAMPLE).max(1));
        let on_grid = sample.clone().all(|i| (value(i) - (value(i) as f32) as f64).abs() <= slack);
        // values that all sit on twice the grid keep a coarser step of their own (a terrain model
        // posted every metre at a northing where f32 steps by 0.5, or every 0.25 m at an easting
        // where it steps by 1/32): rounding to f32 leaves about as many on its odd multiples
        let odd = sample.clone().any(|i| (value(i) / grid).round().rem_euclid(2.0) == 1.0);
        if on_grid && odd {
            step = step.max(grid);
        }
    }
    (step, far)
}

/// Ratio of a cloud's second principal spread to its first (standard deviations along the
/// principal axes) below which the cloud is a line: the registration is refused, since a
/// rotation about the line cannot be determined.
pub const COLLINEAR_RATIO: f64 = 1e-3;

/// Ratio below which a cloud is nearly a line: the registration runs, with a warning that the
/// rotation about its axis is weakly constrained.
pub const THIN_RATIO: f64 = 1e-2;

/// Ratio of the third principal spread to the first below which a cloud is flat; when both
/// clouds are, a warning says that sliding in the plane and turning about its normal are held
/// only by the outlines.
pub const FLAT_RATIO: f64 = 1e-3;

/// The standard deviations of `points` along their principal axes, largest first (in `f64`).
pub fn principal_spreads(points: &[[f32; 3]]) -> [f64; 3] {
    let n = points.len().max(1) as f64;
    // two passes (the mean, then the moments about it), each a few scalar sums per point
    let mut sum = [0.0f64; 3];
    for p in points {
        for a in 0..3 {
            sum[a] += p[a] as f64;
        }
    }
    let mean = sum.map(|s| s / n);
    let [mut xx, mut xy, mut xz, mut yy, mut yz, mut zz] = [0.0f64; 6];
    for p in points {
        let (x, y, z) = (p[0] as f64 - mean[0], p[1] as f64 - mean[1], p[2] as f64 - mean[2]);
        xx += x * x;
        xy += x * y;
        xz += x * z;
        yy += y * y;
        yz += y * z;
        zz += z * z;
    }
    spreads_of(&(nalgebra::Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz) / n))
}

/// The standard deviations along the principal axes of the covariance `cov`, largest first.
pub(crate) fn spreads_of(cov: &nalgebra::Matrix3<f64>) -> [f64; 3] {
    let mut ev: Vec<f64> = cov.symmetric_eigenvalues().iter().map(|v| v.max(0.0).sqrt()).collect();
    ev.sort_by(|a, b| b.total_cmp(a));
    [ev[0], ev[1], ev[2]]
}

/// Refuses a collinear cloud (an error naming it) and warns about a nearly collinear one;
/// returns its principal spreads. `what` names the cloud.
pub fn not_collinear(what: &str, points: &[[f32; 3]], warnings: &mut Vec<Warning>) -> Result<[f64; 3]> {
    let s = principal_spreads(points);
    let ratio = s[1] / s[0];
    if ratio.is_nan() || ratio < COLLINEAR_RATIO {
        // a cloud given as 32-bit floats far from zero, rounded coarser than its size allows (the
        // rule of the coarse-coordinates warning, `f32_rounds`)
        let (lo, hi) = crate::cloud::bounds_of(points);
        let far = lo.iter().chain(&hi).fold(0.0f64, |m, v| m.max((*v as f64).abs()));
        let step = f32_step(far);
        let rounded = if f32_rounds(far, crate::cloud::half_extent_of(lo, hi)) {
            format!(
                " (its 32-bit float coordinates lie up to {} from zero, where floats are {} apart: it may be a line only \
                 because they were rounded; give the coordinates as f64: a Float64Array, {{ points, origin }}, or \
                 PointCloud::from_points_f64)",
                crate::error::num(far),
                crate::error::num(step)
            )
        } else {
            String::new()
        };
        return Err(Error::InvalidCloud(format!(
            "{what} is collinear: its points lie along a line (spread across it {ratio:.1e} of the spread along it, below {COLLINEAR_RATIO:e}), so the rotation about that line cannot be determined{rounded}"
        )));
    }
    if ratio < THIN_RATIO {
        warnings.push(Warning::new(WarningCode::NearlyLine, format!(
            "{what} is nearly a line (spread across it {ratio:.1e} of the spread along it): the rotation about its axis is weakly constrained and may be wrong"
        )));
    }
    Ok(s)
}

/// Warns when both clouds are flat (see [`FLAT_RATIO`]), given their principal spreads, and
/// says whether they are: point-to-plane ICP then runs point-to-point, since every normal is the
/// plane's and a point-to-plane fit cannot move within it (`icp` says whether ICP runs at all, for
/// the warning).
pub fn flat_pair(source: [f64; 3], target: [f64; 3], icp: bool, warnings: &mut Vec<Warning>) -> bool {
    let flat = source[2] / source[0] < FLAT_RATIO && target[2] / target[0] < FLAT_RATIO;
    if flat {
        let how = if icp { " (ICP ran point-to-point, which pairs the outlines)" } else { "" };
        warnings.push(Warning::new(
            WarningCode::BothFlat,
            format!(
            "both clouds are flat: sliding within the plane and turning about its normal are held only by the clouds' \
             outlines{how}, so check the result"
        ),
        ));
    }
    flat
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_terrain_model_posted_on_a_grid_of_its_own_is_not_taken_for_f32() {
        // a DEM exported as text with millimetre heights at easting 500,000 and northing
        // 6,000,000 (f32 steps there: 1/32 and 0.5), posted every 1, 0.5 and 0.25 m
        for (posting, warned) in [(1.0, false), (0.25, false), (0.5, true)] {
            let points: Vec<[f64; 3]> = (0..400)
                .map(|i| {
                    let (c, r) = ((i % 20) as f64, (i / 20) as f64);
                    [500_000.0 + c * posting, 6_000_000.0 + r * posting, 100.0 + ((i * 37) % 1000) as f64 * 0.001]
                })
                .collect();
            let cloud = crate::PointCloud::from_points_f64(&points);
            // (a posting as coarse as f32's own step there cannot be told from f32's rounding)
            assert_eq!(stored_f32_step(&cloud).0 > 0.0, warned, "posting {posting}");
        }
    }

    #[test]
    fn a_cloud_read_from_f32_values_far_from_zero_is_on_their_grid() {
        // values a file stored as float at a northing of 5.4e6 (steps of 0.5), read in f64
        let f32_values: Vec<[f64; 3]> = (0..500)
            .map(|i| {
                let t = i as f64 * 0.37;
                [t.sin() * 20.0, (5.4e6 + t.cos() * 20.0) as f32 as f64, t * 0.1]
            })
            .collect();
        let cloud = crate::PointCloud::from_points_f64(&f32_values);
        let (step, far) = stored_f32_step(&cloud);
        assert_eq!(step, 0.5);
        assert!((far - 5.4e6).abs() < 30.0, "{far}");
        let mut warnings = Vec::new();
        assert_eq!(f32_rounding("source", &cloud, &mut warnings), 0.5);
        assert!(
            warnings.len() == 1
                && warnings[0].code == WarningCode::CoarseCoordinates
                && warnings[0].message.contains("grid of 32-bit floats"),
            "{warnings:?}"
        );
        // the same points in f64: not on the grid, no warning
        let exact: Vec<[f64; 3]> =
            f32_values.iter().map(|p| [p[0], p[1] + 0.123_456_7 * (p[0] / 20.0), p[2]]).collect();
        let cloud = crate::PointCloud::from_points_f64(&exact);
        assert_eq!(stored_f32_step(&cloud).0, 0.0);
        let mut warnings = Vec::new();
        assert_eq!(f32_rounding("source", &cloud, &mut warnings), 0.0);
        assert!(warnings.is_empty(), "{warnings:?}");
    }

    #[test]
    fn a_cloud_rounded_to_a_line_by_f32_says_so() {
        // a 1 m room corner 3e7 from zero in x and y, as f32: x and y round to one value
        let corner = |x0: f64| -> Vec<[f32; 3]> {
            (0..400)
                .map(|k| {
                    let (u, v) = ((k % 20) as f64 / 20.0, (k / 20) as f64 / 20.0);
                    [[u, v, 0.0], [u, 0.0, v], [0.0, u, v]][k % 3]
                })
                .map(|p| [(p[0] + x0) as f32, (p[1] + x0) as f32, p[2] as f32])
                .collect()
        };
        let e = not_collinear("source", &corner(3e7), &mut Vec::new()).unwrap_err().to_string();
        assert!(e.contains("is collinear") && e.contains("from zero, where floats are 2 apart"), "{e}");
        assert!(e.contains("Float64Array"), "{e}");
        // near zero the corner is no line at all; a true line near zero names no rounding
        assert!(not_collinear("source", &corner(0.0), &mut Vec::new()).is_ok());
        let line: Vec<[f32; 3]> = (0..100).map(|i| [i as f32 * 0.01, 0.0, 0.0]).collect();
        let e = not_collinear("target", &line, &mut Vec::new()).unwrap_err().to_string();
        assert!(e.contains("is collinear") && !e.contains("32-bit"), "{e}");
    }

    #[test]
    fn f32_step_is_the_gap_between_neighbouring_f32_values() {
        for v in [1.0f32, 3.7, 5.4e6, 1e-30, 3e38, 1e-40] {
            let next = f32::from_bits(v.to_bits() + 1);
            assert_eq!(f32_step(v as f64), (next - v) as f64, "{v}");
            assert_eq!(f32_step(-(v as f64)), (next - v) as f64, "{v}");
        }
        assert_eq!(f32_step(5.4e6), 0.5);
        assert_eq!(f32_step(0.0), 0.0);
        assert!(f32_step(f64::NAN).is_infinite());
    }

    #[test]
    fn spreads_tell_lines_planes_and_volumes() {
        let line: Vec<[f32; 3]> = (0..100).map(|i| [i as f32 * 0.1, i as f32 * 0.2, 1.0]).collect();
        let mut w = Vec::new();
        assert!(not_collinear("source", &line, &mut w).unwrap_err().to_string().contains("source is collinear"));
        let rod: Vec<[f32; 3]> = (0..100).map(|i| [i as f32, (i % 2) as f32 * 0.5, 0.0]).collect();
        not_collinear("target", &rod, &mut w).unwrap();
        assert!(w[0].code == WarningCode::NearlyLine && w[0].message.contains("target is nearly a line"), "{w:?}");
        let plane: Vec<[f32; 3]> = (0..400).map(|i| [(i % 20) as f32, (i / 20) as f32, 0.0]).collect();
        let mut w = Vec::new();
        let s = not_collinear("source", &plane, &mut w).unwrap();
        assert!(w.is_empty());
        assert!(flat_pair(s, s, true, &mut w));
        assert_eq!(w.len(), 1);
        assert!(w[0].code == WarningCode::BothFlat && w[0].message.contains("ICP ran point-to-point"), "{w:?}");
        let mut w = Vec::new();
        assert!(flat_pair(s, s, false, &mut w) && !w[0].message.contains("ICP"), "{w:?}");
        let cube: Vec<[f32; 3]> =
            (0..1000).map(|i| [(i % 10) as f32, (i / 10 % 10) as f32, (i / 100) as f32]).collect();
        let c = principal_spreads(&cube);
        let mut w = Vec::new();
        assert!(!flat_pair(s, c, true, &mut w));
        assert!(w.is_empty());
        assert!(finite_transform(&Matrix4::identity(), "x").is_ok());
        assert!(finite_transform(&(Matrix4::identity() * f64::NAN), "x").is_err());
    }
}
