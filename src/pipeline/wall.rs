//! Stage 5, after the search: the answer moved onto the other faces of thin walls.
//!
//! A one-view scan of sheet metal or a thin-walled housing sees one face of each wall; the model
//! has both, a wall's thickness apart, and ICP settles on whichever face its start reached first.
//! Both fit about as well; only the edges, bends and holes (whose other face is shaped a little
//! differently) tell them apart. [`other_faces`] finds, under the answer, the faces parallel to the
//! ones the source lies on, and the translations that would move the source onto them; the search
//! refines those poses at the final distance and keeps one that fits better ([`fits_better`]),
//! and warns of one that fits alike ([`fits_alike`]): a flat sheet's two faces cannot be told
//! apart.

use crate::error::num;
use crate::icp::IcpTarget;
use crate::refine::{self, Candidate, Refinement};
use crate::transform;
use crate::warning::{Warning, WarningCode};
use nalgebra::{Matrix3, Matrix4, Vector3};

/// Source points sampled to look for other faces.
const SAMPLE: usize = 256;

/// Farthest the other face is looked for along a point's normal, in final distances: a 2 mm wall
/// registered at a 0.3 mm distance is 7 of them thick.
const REACH: f64 = 10.0;

/// The step along the normal, in final distances.
const STEP: f64 = 0.25;

/// A target point counts as on the other face when it lies within this many final distances of
/// the point stepped to (or [`HIT_SPACING`] of the target's spacing, when that is more), farther
/// from the answer's face along the normal than that, with a normal within [`PARALLEL_COS`] of
/// parallel.
const HIT: f64 = 0.5;

/// See [`HIT`]: the hit radius in the target's spacings (its median nearest-neighbour distance
/// where the sample lies): a model read as 200,000 surface points is sparser than a tight
/// distance.
const HIT_SPACING: f64 = 1.0;

/// The target's spacing is measured at this many of the sample's points on it.
const SPACING_POINTS: usize = 32;

/// See [`HIT`]: the cosine of the largest angle between the two faces' normals.
const PARALLEL_COS: f64 = 0.9;

/// Share of the matched sample points that must see another face: a thin-walled part, not a thin
/// feature of a solid one.
const MIN_SHARE: f64 = 0.5;

/// Share of the sample points that see another face that a wall (those whose other face lies the
/// same way) must have to be moved on its own: a one-view scan of a box housing sees its top
/// well and its sides at a slant (58, 14 and 13 of 85 points).
const WALL_SHARE: f64 = 0.1;

/// Most walls moved, the largest first.
const MAX_WALLS: usize = 3;

/// Most times the answer is moved across walls: a moved answer that fits better is moved again,
/// since a scan placed a wall off along two or three axes (a box housing's top and sides) shows
/// its other walls once the first is right.
pub(crate) const ROUNDS: usize = 3;

/// The answer `t` (`T_target_source`) moved onto the other faces of the walls the `source` lies
/// on (see the module docs): for each wall (the sample points whose other face lies the same way,
/// at least [`WALL_SHARE`] of those that see one, at most [`MAX_WALLS`], the largest first) the
/// translation by its median thickness across it. Empty when fewer than [`MIN_SHARE`] of the sample's points that lie on the target (at
/// the final distance `d_final`) see such a face.
pub(crate) fn other_faces(
    target: &IcpTarget,
    source: &[[f32; 3]],
    t: &Matrix4<f64>,
    d_final: f64,
) -> Vec<Matrix4<f64>> {
    let sample = refine::even_sample(source, SAMPLE);
    let points = target.points();
    let at = |j: usize| Vector3::from(points[j].map(|v| v as f64));
    let normal = |j: usize| normal_of(target, j);
    let step = STEP * d_final;
    let steps = (REACH / STEP) as usize;
    // the sample's points on the target, and the target's spacing there
    let on: Vec<(Vector3<f64>, usize)> = sample
        .iter()
        .filter_map(|p| {
            let moved = t.transform_point(&p.map(|v| v as f64).into()).coords;
            target.nearest_within(&moved.map(|v| v as f32).into(), d_final).map(|j| (moved, j))
        })
        .collect();
    let matched = on.len();
    let mut spacings: Vec<f64> =
        on.iter().step_by((matched / SPACING_POINTS).max(1)).map(|&(_, j)| target.spacing_at(j)).collect();
    let spacing = crate::stats::median(&mut spacings).filter(|s| s.is_finite()).unwrap_or(0.0);
    let hit = (HIT * d_final).max(HIT_SPACING * spacing);
    // each point that sees another face: the unit direction to it and its distance
    let mut faces: Vec<(Vector3<f64>, f64)> = Vec::new();
    for &(moved, j) in &on {
        let (n, x) = (normal(j), at(j));
        let mut nearest: Option<f64> = None;
        for sign in [1.0, -1.0] {
            for k in 1..=steps {
                let s = sign * k as f64 * step;
                if nearest.is_some_and(|o: f64| o.abs() <= s.abs()) {
                    break;
                }
                let q = moved + n * s;
                let Some(m) = target.nearest_within(&q.map(|v| v as f32).into(), hit) else { continue };
                let along = (at(m) - x).dot(&n);
                if along * sign >= hit && normal(m).dot(&n).abs() >= PARALLEL_COS {
                    nearest = Some(along);
                    break;
                }
            }
        }
        faces.extend(nearest.map(|s| (n * s.signum(), s.abs())));
    }
    if matched == 0 || (faces.len() as f64) < MIN_SHARE * matched as f64 {
        return Vec::new();
    }
    // the walls: points whose other face lies the same way
    let mut walls: Vec<(Vector3<f64>, Vec<f64>)> = Vec::new();
    for (u, s) in faces {
        match walls.iter_mut().find(|(w, _)| w.normalize().dot(&u) >= PARALLEL_COS) {
            Some((w, thick)) => {
                *w += u;
                thick.push(s);
            }
            None => walls.push((u, vec![s])),
        }
    }
    let seen = walls.iter().map(|(_, thick)| thick.len()).sum::<usize>() as f64;
    walls.retain(|(_, thick)| thick.len() as f64 >= WALL_SHARE * seen);
    walls.sort_unstable_by_key(|(_, thick)| std::cmp::Reverse(thick.len()));
    walls.truncate(MAX_WALLS);
    walls
        .iter_mut()
        .filter_map(|(w, thick)| {
            let d = w.normalize() * crate::stats::median(thick)?;
            Some(transform::from_rotation_translation(&Matrix3::identity(), &d) * t)
        })
        .collect()
}

/// The unit normal of target point `j`.
// one copy of the normal's estimate, for the wasm engine's size
#[inline(never)]
fn normal_of(target: &IcpTarget, j: usize) -> Vector3<f64> {
    Vector3::from(target.normal(j).map(|v| v as f64))
}

/// A pose on another face fits alike when its fitness is within this fraction of the answer's...
const ALIKE_FITNESS: f64 = 0.02;

/// ... and its inlier RMSE within this fraction.
const ALIKE_RMSE: f64 = 0.05;

/// Whether `r`, the answer moved onto other faces and refined, fits better than the `answer`:
/// more of the source within the final distance, no farther from the target on average (an L
/// bracket's one-view scan on its outer faces: 1.000 and 0.0055 against 0.981 and 0.0067 on the
/// inner ones).
pub(crate) fn fits_better(r: &Candidate, answer: &Candidate) -> bool {
    r.fitness > answer.fitness && r.inlier_rmse <= answer.inlier_rmse
}

/// Whether `r` fits about as well as the `answer` ([`ALIKE_FITNESS`], [`ALIKE_RMSE`]).
pub(crate) fn fits_alike(r: &Candidate, answer: &Candidate) -> bool {
    (r.fitness - answer.fitness).abs() <= ALIKE_FITNESS * answer.fitness
        && (r.inlier_rmse - answer.inlier_rmse).abs() <= ALIKE_RMSE * answer.inlier_rmse
}

/// The warning for a pose `shift` (the clouds' units) away on the other face of a wall that fits
/// `alike` the `answer`.
pub(crate) fn alike_warning(shift: f64, answer: &Candidate, alike: &Candidate) -> String {
    format!(
        "the source fits about as well moved {} onto a parallel face (fitness {:.3} against {:.3}): the other face \
         of a thin wall or sheet, which a scan of one face cannot tell from its own (scan both faces, or check the \
         answer against the part's thickness), or the next of a repeated structure, such as a building's floors \
         (check the answer against what sets them apart, or give a distance below the repeat)",
        num(shift),
        alike.fitness,
        answer.fitness
    )
}

/// What [`across_walls`] found.
pub(crate) struct Across {
    /// The answer: the one given, or a pose on other faces that fits better.
    pub chosen: Candidate,
    /// How many poses on other faces were refined.
    pub tried: usize,
    /// Those of them that `admits` said may count.
    pub refined: Vec<Candidate>,
    /// A warning when a pose on other faces fits alike ([`fits_alike`]).
    pub warning: Option<Warning>,
}

/// The `answer` moved across the thin walls of the `target` the `source` lies on
/// ([`other_faces`]), each pose `level`led and refined at the final distance only
/// ([`refine::refine_final_screened`] on the source capped as for the answer, so a pose that
/// slides back onto the answer's faces stops after a run on a sample; the wider stages would pair
/// points across the wall); one that fits better ([`fits_better`]) and `improves` on the answer replaces it and is
/// moved again, up to [`ROUNDS`] times (a scan a wall off along two or three axes). A pose that
/// fits alike gives a warning, its shift measured at the source's `centre` (`scale`: the clouds'
/// units per normalised unit).
// kept out of the search's one large function (the wasm engine's size)
#[allow(clippy::too_many_arguments)]
#[inline(never)]
pub(crate) fn across_walls(
    target: &IcpTarget,
    source: &[[f32; 3]],
    answer: Candidate,
    how: &Refinement,
    level: &dyn Fn(Matrix4<f64>) -> Matrix4<f64>,
    admits: &dyn Fn(&Matrix4<f64>) -> bool,
    improves: &dyn Fn(&Candidate, &Candidate) -> bool,
    (centre, scale): (Vector3<f64>, f64),
) -> Across {
    let d_final = how.d_final;
    let capped = &refine::even_sample(source, refine::REFINE_POINTS);
    let (mut chosen, mut refined, mut tried) = (answer, Vec::new(), 0);
    for _ in 0..ROUNDS {
        let from = chosen;
        for t in other_faces(target, source, &from.T_target_source, d_final) {
            let r = refine::refine_final_screened(target, capped, answer.start, &level(t), how, &from.T_target_source);
            tried += 1;
            let Some(r) = r else { continue };
            if admits(&r.T_target_source) {
                refined.push(r);
                if fits_better(&r, &chosen) && improves(&chosen, &r) {
                    chosen = r;
                }
            }
        }
        if chosen.T_target_source == from.T_target_source {
            break;
        }
    }
    let other = |r: &&Candidate| !refine::coincide(&r.T_target_source, &chosen.T_target_source, capped, d_final);
    let warning =
        std::iter::once(&answer).chain(&refined).filter(other).find(|r| fits_alike(r, &chosen)).map(|alike| {
            let at = |c: &Candidate| c.T_target_source.transform_point(&centre.into());
            let shift = (at(&chosen) - at(alike)).norm() * scale;
            Warning::new(WarningCode::ThinWall, alike_warning(shift, &chosen, alike))
        });
    Across { chosen, tried, refined, warning }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn alike_and_better_fits() {
        let c = |fitness: f64, inlier_rmse: f64| Candidate {
            start: refine::Start::Initial,
            T_target_source: Matrix4::identity(),
            fitness,
            inlier_rmse,
            iterations: 0,
            converged: true,
        };
        assert!(fits_better(&c(1.0, 0.0055), &c(0.981, 0.0067)));
        assert!(!fits_better(&c(0.99, 0.0070), &c(0.98, 0.0067)), "farther on average");
        assert!(fits_alike(&c(0.9884, 0.001387), &c(0.9863, 0.001386)));
        assert!(!fits_alike(&c(1.0, 0.0055), &c(0.981, 0.0067)));
    }
}
