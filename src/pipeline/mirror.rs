//! Stage 5, after the search: whether a mirror image of the source fits the target clearly better
//! than the answer.
//!
//! No rigid motion aligns a part with its mirror image (a left bracket with the right one's model, a
//! file exported with one axis flipped), yet the best rigid fit of a nearly symmetric part (a
//! tooth, a bone, a bracket) can fit about as well as the truth would at a loose distance. With
//! `sourceOverlap` (a scan onto its model, where that mistake is common; the check costs a quarter
//! to a third of a small pair's time), the source's mirror images, placed where the answer placed
//! the source, are refined like a start; one that fits clearly better than the answer
//! ([`fits_better`]) tells that the clouds are mirror images of each other, and
//! [`super::caps::cap`] holds the answer's confidence down.

use crate::confidence;
use crate::icp::IcpTarget;
use crate::refine::{self, Candidate, Refinement};
use crate::transform;
use nalgebra::{Matrix3, Matrix4, Vector3};

/// The mirror image fits clearly better ([`clearly_better`]) when, with about as many of its
/// points as the answer's within the final distance (no fewer than [`MIRROR_FITNESS_SLACK`] of the
/// source less), those points lie this much closer (inlier RMSE as a fraction of the answer's):
/// scans of a premolar and a molar (0.02 mm noise) on mirrored models 0.54-0.67 of the rigid
/// answer's RMSE, on their own models 1.4-1.9 times it (`BENCHMARK.md`, "Mirror images").
pub(crate) const MIRROR_RMSE: f64 = 0.8;

/// See [`MIRROR_RMSE`].
pub(crate) const MIRROR_FITNESS_SLACK: f64 = 0.02;

/// The mirror image also fits clearly better when this many times as many of its points as the
/// answer's lie within the final distance, no farther on average ([`MIRROR_RMSE_SLACK`]). A
/// mirror image of a crop of a symmetric shape is a crop of its other side, which may overlap the
/// target more than the truth does: on validation pairs, right answers' mirror images reached up
/// to 1.44 times their fitness (those answers were at 0.5 or below already), mirrored real scans'
/// answers were 1.36-4.2 times short of their mirror images where those were found.
pub(crate) const MIRROR_FITNESS: f64 = 1.3;

/// See [`MIRROR_FITNESS`].
pub(crate) const MIRROR_RMSE_SLACK: f64 = 1.02;

/// The mirror image also fits clearly better when both more of its points lie within the final
/// distance (this many times as many) and they lie closer ([`MIRROR_BOTH_RMSE`] of the answer's
/// inlier RMSE): a left foot's partial scan onto a right foot's template fitted 0.825 at 12.2
/// micrometres per millimetre of RMSE, its mirror image 0.989 at 10.7 (1.20 and 0.88 times),
/// which neither rule alone took. With the check forced on every answer of `paper-nt`,
/// `any-nt`, `up-nt` and the real scans (612 mirror images, a build of session 64), none met
/// both.
pub(crate) const MIRROR_BOTH_FITNESS: f64 = 1.15;

/// See [`MIRROR_BOTH_FITNESS`].
pub(crate) const MIRROR_BOTH_RMSE: f64 = 0.9;

/// The best refined mirror image of `source` (its point reflection through its centroid, and that
/// turned a half turn about each of its principal axes: its reflections across its principal
/// planes; the four mirror images that differ from each other by more than a small turn), each
/// placed by the answer's `T_target_source` and refined like a start ([`refine::refine_best`])
/// with `how`, when it fits clearly better than the `answer` ([`clearly_better`]) and `admits`
/// its pose; `None` otherwise. Its figures are at the final distance, as the answer's.
// kept out of the registration's one large function: 0.6 KB less of the wasm engine, gzip
#[inline(never)]
pub(crate) fn fits_better(
    target: &IcpTarget,
    source: &[[f32; 3]],
    answer: &Candidate,
    how: &Refinement,
    admits: &dyn Fn(&Matrix4<f64>) -> bool,
) -> Option<Candidate> {
    let capped = refine::even_sample(source, refine::REFINE_POINTS);
    let (c, axes) = confidence::principal_axes(&capped, &Matrix4::identity());
    let mirrored: Vec<[f32; 3]> = capped.iter().map(|p| [0, 1, 2].map(|k| (2.0 * c[k] - p[k] as f64) as f32)).collect();
    let t = answer.T_target_source;
    let starts: Vec<_> = std::iter::once(t)
        .chain(axes.column_iter().map(|u| t * half_turn(&u.into_owned(), &c)))
        .map(|s| (answer.start, s))
        .collect();
    let how = Refinement { estimate: None, ..*how };
    let m = refine::refine_best(target, &mirrored, &starts, &how)?;
    (clearly_better(&m, answer) && admits(&m.T_target_source)).then_some(m)
}

/// Whether the refined mirror image `m` fits clearly better than the `answer`: its points closer
/// ([`MIRROR_RMSE`]), many more of them near the target ([`MIRROR_FITNESS`]), or more of them and
/// closer ([`MIRROR_BOTH_FITNESS`]).
fn clearly_better(m: &Candidate, answer: &Candidate) -> bool {
    let closer = m.fitness >= answer.fitness - MIRROR_FITNESS_SLACK && m.inlier_rmse < MIRROR_RMSE * answer.inlier_rmse;
    let more = m.fitness > MIRROR_FITNESS * answer.fitness && m.inlier_rmse <= MIRROR_RMSE_SLACK * answer.inlier_rmse;
    let both =
        m.fitness > MIRROR_BOTH_FITNESS * answer.fitness && m.inlier_rmse < MIRROR_BOTH_RMSE * answer.inlier_rmse;
    closer || more || both
}

/// The half turn about the line through `c` along the unit vector `u`.
fn half_turn(u: &Vector3<f64>, c: &Vector3<f64>) -> Matrix4<f64> {
    let r = 2.0 * u * u.transpose() - Matrix3::identity();
    transform::from_rotation_translation(&r, &(c - r * c))
}
