//! The `up` constraint ([`Options::up`]): both clouds were captured level, so an answer may only
//! turn the source about the shared up axis (within [`crate::register::UP_TOLERANCE_DEG`]).
//!
//! In the pipeline's frames the target's up is the caller's direction (normalising only shifts
//! and scales), and the source's is that direction turned by the initial guess's rotation (the
//! source is turned by it before normalising). The search levels every start ([`Upright::level`])
//! and keeps only answers, probe poses and alternatives tilted at most
//! [`crate::register::UP_TOLERANCE_DEG`]
//! ([`Upright::tilt_deg`], judged by [`crate::confidence::Admissible::admits`]).

use crate::register::Options;
use crate::transform;
use nalgebra::{Matrix3, Matrix4, Rotation3, Unit, Vector3};

/// The shared up axis in the pipeline's frames.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Upright {
    /// Up in the (turned, normalised) source frame.
    source_up: Unit<Vector3<f64>>,
    /// Up in the normalised target frame.
    target_up: Unit<Vector3<f64>>,
}

impl Upright {
    /// The constraint of `options.up` (already checked: finite, not zero), with the initial
    /// guess's rotation `rotate_init` (applied to the source before normalising); `None` without
    /// `up`.
    pub(crate) fn of(options: &Options, rotate_init: &Matrix4<f64>) -> Option<Self> {
        let up = Vector3::from(options.up?);
        // scaled by its largest entry first: a direction of any finite length, without overflow
        let up = Unit::try_new(up / up.amax(), 1e-12)?;
        let source_up = Unit::new_normalize(transform::rotation(rotate_init) * up.into_inner());
        Some(Upright { source_up, target_up: up })
    }

    /// Up in the target frame.
    pub(crate) fn up(&self) -> Unit<Vector3<f64>> {
        self.target_up
    }

    /// How far `T_target_source` tilts the source's up away from the target's, degrees.
    #[allow(non_snake_case)]
    pub(crate) fn tilt_deg(&self, T_target_source: &Matrix4<f64>) -> f64 {
        let moved = transform::rotation(T_target_source) * self.source_up.into_inner();
        moved.angle(&self.target_up).to_degrees()
    }

    /// `T_target_source` turned `degrees` about up through `pivot`, a point of the target frame
    /// (where the pose puts the source's centroid, so that the source turns in place).
    #[allow(non_snake_case)]
    pub(crate) fn turned(&self, T_target_source: &Matrix4<f64>, degrees: f64, pivot: &Vector3<f64>) -> Matrix4<f64> {
        let s = Rotation3::from_axis_angle(&self.target_up, degrees.to_radians()).into_inner();
        let t = transform::translation(T_target_source);
        transform::from_rotation_translation(&(s * transform::rotation(T_target_source)), &(s * (t - pivot) + pivot))
    }

    /// `T_target_source` levelled: turned by the smallest rotation that brings the source's up
    /// onto the target's, about `pivot` (where the pose puts the source's centroid, so that the
    /// source stays where the pose put it). An upright pose is returned unchanged; a pose that
    /// turns up exactly upside down is levelled by a half turn about an axis across up.
    #[allow(non_snake_case)]
    pub(crate) fn level(&self, T_target_source: &Matrix4<f64>, pivot: &Vector3<f64>) -> Matrix4<f64> {
        let r = transform::rotation(T_target_source);
        let moved = r * self.source_up.into_inner();
        let up = self.target_up.into_inner();
        let s: Matrix3<f64> = match Rotation3::rotation_between(&moved, &up) {
            Some(s) => s.into_inner(),
            // antiparallel: a half turn about any axis across up
            None => {
                let across =
                    up.cross(&Vector3::x()).try_normalize(1e-6).unwrap_or_else(|| up.cross(&Vector3::y()).normalize());
                Rotation3::from_axis_angle(&Unit::new_normalize(across), std::f64::consts::PI).into_inner()
            }
        };
        let t = transform::translation(T_target_source);
        transform::from_rotation_translation(&(s * r), &(s * (t - pivot) + pivot))
    }
}
