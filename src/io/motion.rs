//! The motions a file can be moved by as it is ([`super::transform_file`]): rigid, or rigid
//! times one uniform scale (a change of unit).

use crate::transform::RIGID_TOLERANCE;
use crate::{Error, Result};
use nalgebra::{Matrix3, Matrix4, Vector3};

/// `m` checked: finite, the bottom row `[0, 0, 0, 1]`, and its linear part `A` within
/// [`RIGID_TOLERANCE`] of `s R` (`R` a rotation, `s > 0`). Returns `A`, `R`, `s` and `t`: `R` the
/// rotation nearest `A / s` (what turns normals and poses), and `s` made 1 when it is within that
/// tolerance of 1 (a rigid matrix written with a few decimals: no change of unit), as a
/// [`Motion`]. Points are
/// mapped by `A` itself, not by `s R`: snapping `A` onto a rotation would turn the points about
/// the frame's origin, which on map-grid coordinates lies kilometres away, and move a survey by
/// metres for a matrix off by 1e-4.
fn similarity(m: &Matrix4<f64>) -> Result<Motion> {
    similarity_named(m, "the transform")
}

/// [`similarity`], its errors naming the matrix `what`; one whose transpose would do says that its
/// numbers may be in the other order.
fn similarity_named(m: &Matrix4<f64>, what: &str) -> Result<Motion> {
    similarity_checked(m, what).map_err(|e| match e {
        Error::InvalidOption(message) if similarity_checked(&m.transpose(), what).is_ok() => {
            Error::InvalidOption(format!(
                "{message}; its transpose is rigid, so its 16 numbers may be in the other order (JS and JSON: \
             column-major, as three.js; the CLI: row by row)"
            ))
        }
        e => e,
    })
}

/// [`similarity_named`] without the hint.
fn similarity_checked(m: &Matrix4<f64>, what: &str) -> Result<Motion> {
    let bad = |why: &str| Err(Error::InvalidOption(format!("{what} is not rigid (or uniformly scaled): {why}")));
    if m.iter().any(|v| !v.is_finite()) {
        return bad("it has a non-finite entry");
    }
    let bottom = [m[(3, 0)], m[(3, 1)], m[(3, 2)], m[(3, 3)] - 1.0];
    if bottom.iter().map(|v| v.abs()).sum::<f64>() > RIGID_TOLERANCE {
        return bad("its bottom row is not [0, 0, 0, 1]");
    }
    let linear: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into_owned();
    let det = linear.determinant();
    if det <= 0.0 {
        return bad("it mirrors or flattens (determinant not > 0)");
    }
    let scale = det.cbrt();
    let rotation = linear / scale;
    if (rotation.transpose() * rotation - Matrix3::identity()).abs().max() > RIGID_TOLERANCE {
        return bad("its linear part is not a rotation times one scale");
    }
    let t = m.fixed_view::<3, 1>(0, 3).into_owned();
    // (a computed transform, rigid to 1e-9, is used bit for bit)
    if (scale - 1.0).abs() <= 1e-9 && crate::transform::check_rigid(m, 1e-9).is_ok() {
        return Ok(Motion { linear, rotation: linear, scale: 1.0, t });
    }
    let rotation = crate::rigid::nearest_rotation(&rotation);
    let scale = if (scale - 1.0).abs() <= RIGID_TOLERANCE { 1.0 } else { scale };
    Ok(Motion { linear, rotation, scale, t })
}

/// `m` checked as a motion points may be moved by: rigid, or rigid times one uniform scale (a
/// result's `T_target_source` with `sourceScale`); the error names the matrix `what` and says why
/// not.
#[cfg_attr(not(target_arch = "wasm32"), allow(dead_code))]
pub(crate) fn check_similarity(m: &Matrix4<f64>, what: &str) -> Result<()> {
    similarity_named(m, what).map(|_| ())
}

/// A checked motion ([`similarity`]) that maps points and turns normals.
pub(super) struct Motion {
    /// `A`, the matrix's linear part (`s R` within [`RIGID_TOLERANCE`]).
    pub(super) linear: Matrix3<f64>,
    /// `R`.
    pub(super) rotation: Matrix3<f64>,
    /// `s` (1 for a rigid matrix).
    scale: f64,
    /// The translation.
    pub(super) t: Vector3<f64>,
}

impl Motion {
    /// `m` checked as [`similarity`] checks it.
    pub(super) fn new(m: &Matrix4<f64>) -> Result<Self> {
        similarity(m)
    }

    /// The uniform scale `s` (exactly 1 for a matrix rigid to [`RIGID_TOLERANCE`]).
    pub(super) fn scale(&self) -> f64 {
        self.scale
    }

    /// A point mapped as the matrix maps it: `A p + t`.
    pub(super) fn point(&self, p: [f64; 3]) -> [f64; 3] {
        (self.linear * Vector3::from(p) + self.t).into()
    }

    /// A normal turned: `R n`.
    pub(super) fn normal(&self, n: [f64; 3]) -> [f64; 3] {
        (self.rotation * Vector3::from(n)).into()
    }
}

/// The axis-aligned bounds of the positions a file holds (f64, in the file's frame), taken in one
/// at a time: what the moved positions need to be written to their precision.
#[derive(Clone, Copy, Debug)]
pub(super) struct Bounds([[f64; 2]; 3]);

impl Default for Bounds {
    fn default() -> Self {
        Self([[f64::INFINITY, f64::NEG_INFINITY]; 3])
    }
}

impl Bounds {
    /// Takes in one position (one with a non-finite value is left out).
    pub(super) fn add(&mut self, p: [f64; 3]) {
        if p.iter().all(|v| v.is_finite()) {
            for (b, v) in self.0.iter_mut().zip(p) {
                *b = [b[0].min(v), b[1].max(v)];
            }
        }
    }

    /// The box's diagonal after `motion` (its scale times the box's own); 0 without a position.
    pub(super) fn diagonal(&self, motion: &Motion) -> f64 {
        self.0.iter().map(|[lo, hi]| (hi - lo).max(0.0).powi(2)).sum::<f64>().sqrt() * motion.scale.abs()
    }

    /// The largest value of a position moved by `motion` on each axis (it lies on a corner of the
    /// moved box); 0 without a position.
    fn largest_moved_per_axis(&self, motion: &Motion) -> [f64; 3] {
        if self.0[0][0] > self.0[0][1] {
            return [0.0; 3];
        }
        let [x, y, z] = self.0;
        (0..8)
            .map(|k| motion.point([x[k & 1], y[(k >> 1) & 1], z[(k >> 2) & 1]]))
            .fold([0.0f64; 3], |a, p| [0, 1, 2].map(|i| a[i].max(p[i].abs())))
    }

    /// The largest value of a position moved by `motion`; 0 without a position.
    pub(super) fn largest_moved(&self, motion: &Motion) -> f64 {
        self.largest_moved_per_axis(motion).into_iter().fold(0.0, f64::max)
    }

    /// What `f32` does to the positions moved by `motion` on the axes `single` marks (those the
    /// file stores as `f32`): [`F32Steps`]; `None` without a position.
    fn f32_steps(&self, motion: &Motion, single: [bool; 3]) -> Option<F32Steps> {
        if self.0[0][0] > self.0[0][1] {
            return None;
        }
        let marked = |v: [f64; 3]| (0..3).filter(|&i| single[i]).fold(0.0f64, |a, i| a.max(v[i]));
        let far = marked(self.largest_moved_per_axis(motion));
        Some(F32Steps {
            far,
            step: crate::checks::f32_step(far),
            own: crate::checks::f32_step(marked(self.0.map(|[lo, hi]| lo.abs().max(hi.abs())))),
            half: self.0.iter().fold(0.0f64, |a, [lo, hi]| a.max((hi - lo) * 0.5)) * motion.scale.abs(),
        })
    }

    /// The `f32` step at the largest moved value of the axes `single` marks (those the file stores
    /// as `f32`), when `f32` would round the moved positions there: beyond
    /// [`crate::checks::F32_ROUNDING_WARNING`] of the moved box's largest half-extent (the rule of
    /// [`crate::PointCloud::placed`]; a local scan moved onto a map grid), and more coarsely than
    /// the file's own values on those axes were (a file already on the grid keeps its own
    /// precision); a cloud of no extent (one point) on the second condition alone. Else `None`.
    pub(super) fn f32_rounds(&self, motion: &Motion, single: [bool; 3]) -> Option<f64> {
        let F32Steps { far, step, own, half } = self.f32_steps(motion, single)?;
        let loses = half <= 0.0 || crate::checks::f32_rounds(far, half);
        (loses && step > own).then_some(step)
    }

    /// The rule for a file that can store its moved positions as doubles (a PLY): true when
    /// [`Self::f32_rounds`] says so, or when `f32` would hold the moved positions (on the axes
    /// `single` marks) more than [`COARSER_THAN_OWN`] times more coarsely than the file held its
    /// own, scaled as the motion scales them, and more coarsely than [`COARSENED_NEGLIGIBLE`] of
    /// the moved box's largest half-extent: a scan in metres near zero moved onto plant
    /// coordinates in millimetres 2.4e6 from zero keeps its own precision instead of a 0.25 mm grid.
    pub(super) fn f32_coarsens(&self, motion: &Motion, single: [bool; 3]) -> bool {
        if self.f32_rounds(motion, single).is_some() {
            return true;
        }
        self.f32_steps(motion, single).is_some_and(|F32Steps { step, own, half, .. }| {
            step > COARSER_THAN_OWN * own * motion.scale.abs() && step > COARSENED_NEGLIGIBLE * half
        })
    }
}

/// What `f32` does to a file's positions moved by a motion ([`Bounds::f32_steps`]).
struct F32Steps {
    /// The largest moved value on the marked axes.
    far: f64,
    /// The `f32` step there.
    step: f64,
    /// The `f32` step at the file's own largest value on those axes (in the file's units).
    own: f64,
    /// The moved box's largest half-extent.
    half: f64,
}

/// How many times more coarsely than a file held its own positions (in the moved units) `f32`
/// may hold them moved before a file that can store doubles stores them so ([`Bounds::f32_coarsens`]).
const COARSER_THAN_OWN: f64 = 8.0;

/// The `f32` step, as a fraction of the moved box's largest half-extent, below which a moved file
/// keeps `f32` positions however much coarser they get than the file's own
/// ([`Bounds::f32_coarsens`]): a step this fine is at `f32`'s own precision for a cloud near zero.
const COARSENED_NEGLIGIBLE: f64 = 2.5e-6;

/// An error when `f32` would round the positions of a `format` file that stores them as `f32` (on
/// the axes `single` marks), moved by `motion`, beyond [`Bounds::f32_rounds`]'s rule: such a file cannot hold them (a local
/// scan moved onto a map grid), and writing it would move every point by up to half that step. A
/// cloud of no extent is never refused.
pub(super) fn check_f32(bounds: &Bounds, motion: &Motion, single: [bool; 3], format: &'static str) -> Result<()> {
    // a cloud of no extent (one point, or one place) has no size to lose digits against: moved
    // anywhere, float32 holds it to its usual seven digits
    if bounds.0.iter().all(|[lo, hi]| hi <= lo) {
        return Ok(());
    }
    match bounds.f32_rounds(motion, single) {
        Some(step) => Err(Error::unmovable(
            format,
            format!(
                "the transform moves its points up to {} from zero, where its float32 coordinates hold them only to \
                 steps of {} (the cloud is {} across): save the moved points in double precision instead, as a PLY \
                 (in JS: writePly(transformPointCloud(...)); the CLI: --aligned with a .ply path), which keeps only \
                 the points",
                crate::error::num(bounds.largest_moved(motion)),
                crate::error::num(step),
                crate::error::num(bounds.diagonal(motion))
            ),
        )),
        None => Ok(()),
    }
}
