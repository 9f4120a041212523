//! Moving transforms between the caller's frame and the clouds' local frames.
//!
//! A [`PointCloud`](crate::cloud::PointCloud) stores `f32` offsets from an `f64` origin; the
//! pipeline registers the offsets (the local frames) and these functions convert
//! `T_target_source` between the frames in `f64`, so large coordinates (5e6) lose nothing:
//! `T_caller = Tr(origin_target) * T_local * Tr(-origin_source)`.

use nalgebra::{Matrix4, Vector3};

/// `Tr(-origin_target) * t_caller * Tr(origin_source)`: a caller-frame `T_target_source` as a
/// transform from the source's local frame to the target's. Returns `t_caller` itself when both
/// origins are zero.
pub fn to_local(t_caller: &Matrix4<f64>, origin_source: [f64; 3], origin_target: [f64; 3]) -> Matrix4<f64> {
    if origin_source == [0.0; 3] && origin_target == [0.0; 3] {
        return *t_caller;
    }
    Matrix4::new_translation(&-Vector3::from(origin_target))
        * t_caller
        * Matrix4::new_translation(&Vector3::from(origin_source))
}

/// `Tr(origin_target) * t_local * Tr(-origin_source)`: the inverse of [`to_local`]. Returns
/// `t_local` itself when both origins are zero.
pub fn to_caller(t_local: &Matrix4<f64>, origin_source: [f64; 3], origin_target: [f64; 3]) -> Matrix4<f64> {
    if origin_source == [0.0; 3] && origin_target == [0.0; 3] {
        return *t_local;
    }
    // R (p - o_s) + t + o_t, with the translation summed in f64
    let r = t_local.fixed_view::<3, 3>(0, 0).into_owned();
    let t = t_local.fixed_view::<3, 1>(0, 3).into_owned();
    let t_caller = t + Vector3::from(origin_target) - r * Vector3::from(origin_source);
    crate::transform::from_rotation_translation(&r, &t_caller)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transform::{euler_xyz, from_rotation_translation};

    #[test]
    fn local_and_caller_frames_round_trip() {
        let t = from_rotation_translation(&euler_xyz(0.3, -0.2, 0.1), &Vector3::new(4.0, -1.0, 2.5));
        let (os, ot) = ([5.0e6, 4.2e6, 120.0], [5.0e6 + 3.0, 4.2e6 - 7.0, 118.0]);
        let local = to_local(&t, os, ot);
        assert!((to_caller(&local, os, ot) - t).abs().max() < 1e-8);
        // a source offset p maps like the caller's point os + p does
        let p = Vector3::new(1.5, -2.0, 0.25);
        let via_local = local.transform_point(&p.into()).coords + Vector3::from(ot);
        let via_caller = t.transform_point(&(p + Vector3::from(os)).into()).coords;
        assert!((via_local - via_caller).norm() < 1e-8);
        assert_eq!(to_local(&t, [0.0; 3], [0.0; 3]), t);
    }
}
