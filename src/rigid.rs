//! Closed-form rigid fits shared by GMR ([`crate::gmr::solve`]) and ICP ([`crate::icp`]):
//! weighted Kabsch, the proper rotation of a cross-covariance with defined answers for degenerate
//! input, and re-orthonormalisation. Everything accumulates in `f64`; every answer is a finite
//! rigid transform with `det R = +1`.

use crate::transform::from_rotation_translation;
use nalgebra::{Matrix3, Matrix4, Unit, UnitQuaternion, Vector3};

/// Closed-form point-to-point rigid fit (weighted Kabsch / Umeyama without scale):
/// the `T_target_source` minimising `sum_i w_i |R s_i + t - t_i|^2`, with the same reflection fix
/// and degenerate handling as [`crate::gmr::solve`].
///
/// `weights = None` weighs every pair equally. Pairs with a non-finite coordinate, or a weight
/// that is not finite and positive, are skipped; if the slices differ in length the extra
/// points are ignored. No usable pair gives the identity; a single pair (or all pairs at one
/// point) a pure translation.
pub fn kabsch(source: &[[f64; 3]], target: &[[f64; 3]], weights: Option<&[f64]>) -> Matrix4<f64> {
    let mut n = source.len().min(target.len());
    if let Some(w) = weights {
        n = n.min(w.len());
    }
    let weight = |i: usize| -> f64 {
        let w = weights.map_or(1.0, |w| w[i]);
        let ok = w.is_finite() && w > 0.0 && source[i].iter().chain(target[i].iter()).all(|v| v.is_finite());
        if ok {
            w
        } else {
            0.0
        }
    };
    let mut total = 0.0f64;
    let mut cs = Vector3::zeros();
    let mut ct = Vector3::zeros();
    for i in 0..n {
        let w = weight(i);
        if w > 0.0 {
            total += w;
            cs += Vector3::from(source[i]) * w;
            ct += Vector3::from(target[i]) * w;
        }
    }
    if !(total > 0.0 && total.is_finite()) {
        return Matrix4::identity();
    }
    cs /= total;
    ct /= total;
    let mut m = Matrix3::zeros();
    for i in 0..n {
        let w = weight(i);
        if w > 0.0 {
            let a = Vector3::from(source[i]) - cs;
            let b = Vector3::from(target[i]) - ct;
            m += (a * b.transpose()) * (w / total);
        }
    }
    rigid_from_parts(&m, &cs, &ct)
}

/// The rigid `T_target_source` that best maps paired points `source[i]` onto `target[i]` (least
/// squares, [`kabsch`]), and the RMS distance between the pairs under it: a guess from picked or
/// surveyed landmarks, for [`crate::Options::initial_transform`]. Errors: lists of different
/// lengths, fewer than 3 pairs, a coordinate that is not finite, and pairs on one line (or one
/// point) in either list, where the turn about that line is not determined.
#[allow(non_snake_case)]
pub fn fit_pairs(source: &[[f64; 3]], target: &[[f64; 3]]) -> crate::Result<(Matrix4<f64>, f64)> {
    use crate::Error::InvalidOption;
    if source.len() != target.len() {
        return Err(InvalidOption(format!(
            "the pairs: {} source points against {} target points (each source point pairs with the target point \
             at the same index)",
            source.len(),
            target.len()
        )));
    }
    if source.len() < 3 {
        return Err(InvalidOption(format!("the pairs: {} given, at least 3 are needed", source.len())));
    }
    for (what, points) in [("source", source), ("target", target)] {
        if let Some(i) = points.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
            return Err(InvalidOption(format!("the pairs: {what} point {i} is not finite")));
        }
        // the farthest point from the centroid gives a direction; the points' largest distance
        // from the line along it, against that reach, says whether they span more than a line
        let n = points.len() as f64;
        let c = points.iter().fold(Vector3::zeros(), |a, p| a + Vector3::from(*p)) / n;
        let (reach, dir) = points.iter().map(|p| Vector3::from(*p) - c).fold((0.0f64, Vector3::zeros()), |b, d| {
            if d.norm() > b.0 {
                (d.norm(), d)
            } else {
                b
            }
        });
        let off = points.iter().map(|p| (Vector3::from(*p) - c).cross(&dir).norm() / reach.max(f64::MIN_POSITIVE));
        if reach <= 0.0 || off.fold(0.0, f64::max) <= 1e-6 * reach {
            return Err(InvalidOption(format!(
                "the pairs: the {what} points lie on one line (or at one point): the turn about it is not determined; \
                 pick a point off that line"
            )));
        }
    }
    let T_target_source = kabsch(source, target, None);
    let sum: f64 = source
        .iter()
        .zip(target)
        .map(|(s, t)| (T_target_source.transform_point(&(*s).into()).coords - Vector3::from(*t)).norm_squared())
        .sum();
    Ok((T_target_source, (sum / source.len() as f64).sqrt()))
}

/// `[[R, ct - R cs], [0, 1]]` with `R` from the cross-covariance `m`; identity if anything is
/// not finite.
pub(crate) fn rigid_from_parts(m: &Matrix3<f64>, cs: &Vector3<f64>, ct: &Vector3<f64>) -> Matrix4<f64> {
    let r = rotation_from_cross_covariance(m);
    let t = ct - r * cs;
    if t.iter().all(|v| v.is_finite()) {
        from_rotation_translation(&r, &t)
    } else {
        Matrix4::identity()
    }
}

/// Singular-value ratio `s_2 / s_1` below which the cross-covariance counts as rank one.
pub const RANK_ONE_TOL: f64 = 1e-7;

/// The proper rotation `R` minimising `sum w |R a_i - b_i|^2` (equivalently maximising
/// `tr(R M)`) for the cross-covariance `M = sum w a_i b_i^T` (source on the left): with `M = U S V^T`
/// (singular values descending), `R = V diag(1, 1, det(V U^T)) U^T`.
///
/// Defined answers where the optimum is not unique:
/// * `M` zero or not finite (no spread, e.g. all mass in one component): the identity.
/// * `M` of rank one (`s_2 <= 1e-7 s_1`: the points/means are collinear): the smallest rotation
///   taking the source direction `u_1` onto the target direction `v_1` (a half-turn about an
///   axis perpendicular to `u_1` when they are opposite). Any rotation about the line would be
///   as good; this one moves least.
/// * Rank two (coplanar): the SVD answer is unique once the reflection is fixed, and is used.
pub fn rotation_from_cross_covariance(m: &Matrix3<f64>) -> Matrix3<f64> {
    if !m.iter().all(|v| v.is_finite()) {
        return Matrix3::identity();
    }
    let scale = m.abs().max();
    if scale.is_nan() || scale <= 0.0 {
        return Matrix3::identity();
    }
    // Scale to unit size first: the SVD is scale-invariant, and this keeps tiny or huge
    // entries (weights pi / sigma^2 up to 1e8) away from under/overflow.
    let ms = m / scale;
    let Some(svd) = ms.try_svd(true, true, f64::EPSILON, 500) else {
        return Matrix3::identity();
    };
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return Matrix3::identity();
    };
    let s = svd.singular_values;
    if s[0].is_nan() || s[0] <= 0.0 {
        return Matrix3::identity();
    }
    let v = v_t.transpose();
    if s[1] <= RANK_ONE_TOL * s[0] {
        return smallest_rotation_between(&u.column(0).into_owned(), &v.column(0).into_owned());
    }
    let d = (v * u.transpose()).determinant().signum();
    let mut dm = Matrix3::identity();
    dm[(2, 2)] = if d < 0.0 { -1.0 } else { 1.0 };
    let r = v * dm * u.transpose();
    if r.iter().all(|x| x.is_finite()) {
        r
    } else {
        Matrix3::identity()
    }
}

/// The smallest rotation taking direction `a` onto direction `b` (half-turn about a
/// perpendicular axis when they are opposite; identity for zero vectors).
fn smallest_rotation_between(a: &Vector3<f64>, b: &Vector3<f64>) -> Matrix3<f64> {
    let (Some(a), Some(b)) = (Unit::try_new(*a, 1e-300), Unit::try_new(*b, 1e-300)) else {
        return Matrix3::identity();
    };
    let axis = a.cross(&b);
    let cos = a.dot(&b).clamp(-1.0, 1.0);
    let sin = axis.norm();
    let q = if sin > 1e-12 {
        UnitQuaternion::from_axis_angle(&Unit::new_normalize(axis), sin.atan2(cos))
    } else if cos > 0.0 {
        UnitQuaternion::identity()
    } else {
        // Opposite: half-turn about any axis perpendicular to a (the one built from the
        // coordinate axis least aligned with a, so it is well conditioned).
        let e = if a.x.abs() <= a.y.abs() && a.x.abs() <= a.z.abs() {
            Vector3::x()
        } else if a.y.abs() <= a.z.abs() {
            Vector3::y()
        } else {
            Vector3::z()
        };
        UnitQuaternion::from_axis_angle(&Unit::new_normalize(a.cross(&e)), std::f64::consts::PI)
    };
    q.to_rotation_matrix().into_inner()
}

/// The rotation closest to `r` (polar factor, reflection fixed): re-orthonormalises a rotation
/// block that has drifted after many compositions. Non-finite input gives the identity.
pub fn nearest_rotation(r: &Matrix3<f64>) -> Matrix3<f64> {
    // The rotation Q closest to R maximises tr(Q R^T); with M = R^T = U S V^T the solver
    // returns V D U^T, the polar factor of R.
    rotation_from_cross_covariance(&r.transpose())
}

#[cfg(test)]
mod tests {
    #[test]
    fn pairs_give_their_motion_and_errors_name_what_is_wrong() {
        let t = from_rotation_translation(&crate::transform::euler_xyz(0.4, -1.1, 2.0), &Vector3::new(5e5, 4e6, 30.0));
        let source = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.5, 0.5, 3.0]];
        let target: Vec<[f64; 3]> = source.iter().map(|p| t.transform_point(&(*p).into()).coords.into()).collect();
        let (fit, rmse) = fit_pairs(&source, &target).unwrap();
        assert!((fit - t).abs().max() < 1e-6 && rmse < 1e-6, "{fit} {rmse}");
        // three points are enough; two, or three on a line, are not
        assert!(fit_pairs(&source[..3], &target[..3]).is_ok());
        let err = |s: &[[f64; 3]], t: &[[f64; 3]]| fit_pairs(s, t).unwrap_err().to_string();
        assert!(err(&source[..2], &target[..2]).contains("at least 3"));
        assert!(err(&source, &target[..3]).contains("4 source points against 3"));
        let line = [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]];
        assert!(err(&line, &target[..3]).contains("source points lie on one line"));
        let mut bad = target.clone();
        bad[1][2] = f64::NAN;
        assert!(err(&source, &bad).contains("target point 1 is not finite"));
    }

    use super::*;
    use crate::transform::{check_rigid, euler_xyz, rotation, translation};

    #[test]
    fn kabsch_recovers_transform() {
        let src: Vec<[f64; 3]> = (0..50)
            .map(|i| {
                let f = i as f64;
                [(f * 0.7).sin(), (f * 1.3).cos(), (f * 0.3).sin() * 0.5]
            })
            .collect();
        let t = from_rotation_translation(&euler_xyz(2.5, -0.4, 1.0), &Vector3::new(0.3, -1.0, 2.0));
        let dst: Vec<[f64; 3]> = src
            .iter()
            .map(|p| {
                let q = rotation(&t) * Vector3::from(*p) + translation(&t);
                [q.x, q.y, q.z]
            })
            .collect();
        let est = kabsch(&src, &dst, None);
        assert!((est - t).abs().max() < 1e-10);
        let w: Vec<f64> = (0..50).map(|i| 1.0 + i as f64).collect();
        assert!((kabsch(&src, &dst, Some(&w)) - t).abs().max() < 1e-10);
        assert_eq!(kabsch(&[], &[], None), Matrix4::identity());
        let one = kabsch(&src[..1], &dst[..1], None);
        assert!(check_rigid(&one, 1e-12).is_ok());
        assert!((rotation(&one) - Matrix3::identity()).abs().max() < 1e-15);
    }

    #[test]
    fn nearest_rotation_repairs_drift() {
        let r = euler_xyz(0.3, 0.2, 0.1);
        let drifted = r * 1.001 + Matrix3::from_element(1e-4);
        let fixed = nearest_rotation(&drifted);
        assert!((fixed.transpose() * fixed - Matrix3::identity()).abs().max() < 1e-12);
        assert!((fixed.determinant() - 1.0).abs() < 1e-12);
        assert!((fixed - r).abs().max() < 1e-3);
        assert!((nearest_rotation(&r) - r).abs().max() < 1e-12);
    }
}
