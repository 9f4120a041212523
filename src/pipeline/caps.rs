//! Stage 5, last step: the limits on the answer's confidence that its evidence cannot show.
//!
//! The confidence ([`crate::confidence::confidence`]) is calibrated on how refined answers fit.
//! Some answers fit well for reasons that say nothing about their pose: the answer was never
//! refined, the source is too small for the distance the fit is judged at, its coordinates were
//! rounded to a grid as coarse as that distance, a tilted pose fits clearly better than the
//! upright one `up` asked for, clearly less of the source lies on the target than the caller
//! said does (`sourceOverlap`, [`short_of_overlap`]: also what the search goes by,
//! [`within_overlap`]), a mirror image of the source fits clearly better ([`super::mirror`]), or
//! the answer turns far from the caller's `initialTransform` ([`GUESS_TURN_DEG`]). [`cap`] holds
//! the confidence of such an answer at [`UNREFINED_CONFIDENCE`], below the line of the
//! low-confidence warning, and says why in a warning.

use super::prepare::Prepared;
use crate::confidence::{Evidence, FreeScrew};
use crate::error::num;
use crate::icp::IcpTarget;
use crate::refine::Candidate;
use crate::register::{GUESS_TURN_DEG, UP_TOLERANCE_DEG};
use crate::warning::{Warning, WarningCode};
use nalgebra::Vector3;

/// The most confidence an answer that no start's refinement reached can have (the network's
/// estimate or the initial transform, unrefined, when no start could be refined or none ended
/// upright), and an answer under any other of [`cap`]'s limits: below the line of the
/// low-confidence warning.
pub(crate) const UNREFINED_CONFIDENCE: f64 = 0.25;

/// A source whose largest half-extent is below this many evidence distances
/// ([`super::options::evidence_distance`]) has an answer no fit can confirm, and its confidence is
/// at most [`UNREFINED_CONFIDENCE`]: turned by 15 degrees about its centre, its farthest points
/// move less than that distance (`1 / sin 15°` is 3.9).
pub(crate) const SMALL_SOURCE_DISTANCES: f64 = 4.0;

/// Clouds whose `f32` coordinates were rounded to a grid coarser than this many evidence
/// distances (given as `f32` far from zero: [`Prepared::rounding`]) have an answer no fit can
/// confirm, and its confidence is at most [`UNREFINED_CONFIDENCE`]: every point was moved by up to
/// half that step before the engine saw it, as far as the fit is judged at.
pub(crate) const ROUNDING_DISTANCES: f64 = 1.0;

/// With `sourceOverlap`: how far below it the share of the source within twice the evidence
/// distance ([`Evidence::fitness_loose`]) may fall before the answer falls short of it. Right
/// answers of scans onto their complete models keep 0.92 or more of the scan there (noise up to
/// 0.3 mm on a 35-100 mm part, a print 3% small, the table left out; `BENCHMARK.md`, "A scan
/// onto its model: `sourceOverlap`").
pub(crate) const OVERLAP_SLACK: f64 = 0.15;

/// With `sourceOverlap` (`source_overlap`): the share of the source near the target under the
/// answer whose evidence is `e`, and the declared share, when the first falls short of the second
/// by more than [`OVERLAP_SLACK`]; `None` when it does not, or when no share was declared.
pub(crate) fn short_of_overlap(e: &Evidence, source_overlap: Option<f64>) -> Option<(f64, f64)> {
    source_overlap.filter(|share| e.fitness_loose < share - OVERLAP_SLACK).map(|share| (e.fitness_loose, share))
}

/// `confidence` held at [`UNREFINED_CONFIDENCE`] when the answer whose evidence is `e` falls short
/// of `sourceOverlap` ([`short_of_overlap`]): what the search goes by, so that it goes on.
pub(crate) fn within_overlap(confidence: f64, e: &Evidence, source_overlap: Option<f64>) -> f64 {
    match short_of_overlap(e, source_overlap) {
        Some(_) => confidence.min(UNREFINED_CONFIDENCE),
        None => confidence,
    }
}

/// With `up`: a pose tilted off it that fits clearly better than the upright answer.
pub(crate) struct Tilted {
    /// How far it tilts the source's up off the target's, degrees.
    pub tilt_deg: f64,
    /// Its fitness.
    pub fitness: f64,
}

/// What the search found against its answer, for [`cap`].
pub(crate) struct Doubts {
    /// Whether any start was refined (false: the answer is a start, unrefined).
    pub refined_any: bool,
    /// With `up`: a tilted pose that fits clearly better than the upright answer.
    pub tilted: Option<Tilted>,
    /// With `sourceOverlap`: the share of the source near the target and the declared share it
    /// falls short of ([`short_of_overlap`]).
    pub short: Option<(f64, f64)>,
    /// A mirror image of the source that fits clearly better ([`super::mirror::fits_better`]).
    pub mirrored: Option<Candidate>,
    /// With `initialTransform`: how far the answer turns from it, degrees, when more than
    /// [`GUESS_TURN_DEG`] (30-100 probe points on a vertebra, turned over, fit 0.89-0.97 of them).
    pub far_from_guess: Option<f64>,
    /// A motion the fit leaves free ([`crate::confidence::Evidence::constraint`]).
    pub free: Option<FreeScrew>,
    /// A target too sparse for the evidence distance ([`too_sparse`]): its spacing in evidence
    /// distances, and the answer's fitness there.
    pub sparse: Option<(f64, f64)>,
}

/// A target whose spacing (the median distance from a point to its 4th nearest neighbour) is
/// more than this many times the distance the answer is judged at is too sparse for the fit to
/// judge it ([`too_sparse`]): independent samples of a surface seldom lie that close to each
/// other, so few source points pair up under a right pose or a wrong one, and the confidence is
/// not calibrated there (1,024-point validation pairs: 3 to 4). On partial views of four meshes
/// sampled independently, 100 to 300 points each (spacings 5 to 11), 25 answers of 72 that were
/// wrong had 0.5 or more, up to 0.92; held at this line, 5 (`BENCHMARK.md`, "Sparse clouds").
pub(crate) const SPARSE_SPACINGS: f64 = 7.0;

/// [`too_sparse`] leaves an answer alone when at least this share of the source fits within the
/// evidence distance: clouds whose points coincide (the same markers, survey points or samples in
/// both) pair up however sparse they are (0.58 or more in those trials; independent samples 0.19
/// or less).
pub(crate) const SPARSE_FITS: f64 = 0.4;

/// Points of the target whose neighbours [`sparse_spacings`] measures its spacing from.
const SPARSE_SAMPLE: usize = 256;

/// The target's spacing in evidence distances `d` when it is more than [`SPARSE_SPACINGS`]: a
/// target too sparse for the distance.
pub(crate) fn sparse_spacings(target: &IcpTarget, d: f64) -> Option<f64> {
    let spacings = target.median_reach(4, SPARSE_SAMPLE) / d;
    (spacings > SPARSE_SPACINGS).then_some(spacings)
}

/// On a target too sparse for the distance (its [`sparse_spacings`]), the spacings and the
/// answer's `fitness` at the evidence distance when that is below [`SPARSE_FITS`]: the fit cannot
/// tell a right pose from a wrong one there.
pub(crate) fn too_sparse(sparse_spacings: Option<f64>, fitness: f64) -> Option<(f64, f64)> {
    sparse_spacings.filter(|_| fitness < SPARSE_FITS).map(|s| (s, fitness))
}

/// The confidence of the `answer` held at [`UNREFINED_CONFIDENCE`], with a warning naming the
/// reason, when no start was refined (the warning was given where the answer was chosen), when
/// the source is smaller than [`SMALL_SOURCE_DISTANCES`] evidence distances, when the clouds were
/// rounded to steps of more than [`ROUNDING_DISTANCES`] evidence distances, or when one of the
/// other [`Doubts`] holds.
pub(crate) fn cap(
    p: &Prepared,
    confidence: f64,
    answer: &Candidate,
    doubts: Doubts,
    warnings: &mut Vec<Warning>,
) -> f64 {
    let Doubts { refined_any, tilted, short, mirrored, far_from_guess, free, sparse } = doubts;
    let fitness = answer.fitness;
    let mut capped = !refined_any;
    let s = p.norm.scale;
    // a source within a few evidence distances of its centre fits wherever it touches the target's
    // surface, turned or not: nothing in the fit confirms its pose (typically clouds in different
    // units, the source the smaller)
    let source_extent = p.src_n.half_extent();
    if source_extent < SMALL_SOURCE_DISTANCES * p.d_evidence {
        warnings.push(Warning::new(WarningCode::DistanceTooWide, format!(
            "the source's half-extent ({}) is less than {SMALL_SOURCE_DISTANCES} times the distance the answer is judged at ({}): \
             it fits about as well turned or moved over the target's surface, so the fit cannot confirm its pose \
             (clouds in different units? else give a smaller maxCorrespondenceDistance)",
            num(source_extent * s),
            num(p.d_evidence * s)
        )));
        capped = true;
    }
    // clouds given as f32 far from zero: their points sit on a grid as coarse as the fit's distance
    if p.rounding > ROUNDING_DISTANCES * p.d_evidence {
        // (a grid as fine as f32 is near zero: it is the distance that is too fine, not the clouds)
        warnings.push(if p.rounding < crate::checks::F32_ROUNDING_WARNING {
            Warning::new(
                WarningCode::DistanceTooFine,
                format!(
                "the distance the answer is judged at ({}) is finer than the clouds' f32 coordinates resolve (steps of \
                 about {}): the fit cannot confirm the pose; give a maxCorrespondenceDistance of a few point spacings",
                num(p.d_evidence * s),
                num(p.rounding * s)
            ),
            )
        } else {
            Warning::new(
                WarningCode::CoarseCoordinates,
                format!(
                "the clouds' coordinates were rounded to steps of about {} (f32 far from zero), more than the distance \
                 the answer is judged at ({}): the fit cannot confirm the pose; give the coordinates as f64 (a \
                 Float64Array, or a file that stores doubles)",
                num(p.rounding * s),
                num(p.d_evidence * s)
            ),
            )
        });
        capped = true;
    }
    // with `up`: a tilted pose that fits clearly better than the upright answer (the clouds were
    // not both captured level, or not about that axis)
    if let Some(t) = tilted {
        warnings.push(Warning::new(
            WarningCode::NotUpright,
            format!(
                "a pose tilted {:.0} degrees off `up` fits clearly better than the upright answer (fitness {:.3} \
                 against {:.3}): if the clouds were not both captured level within {UP_TOLERANCE_DEG} degrees of `up`, \
                 leave `up` out",
                t.tilt_deg, t.fitness, fitness
            ),
        ));
        capped = true;
    }
    // with `sourceOverlap`: less of the source lies on the target than the caller knows does
    if let Some((share, declared)) = short {
        warnings.push(Warning::new(
            WarningCode::LowOverlap,
            format!(
            "only {:.0}% of the source lies within {} of the target under the answer, where sourceOverlap says {:.0}%: \
             the wrong model, a mirror-image export (one axis flipped), a scale or unit error, points the target \
             lacks (a table or clutter left in the source), or a pose the search did not find",
            100.0 * share,
            num(2.0 * p.d_evidence * s),
            100.0 * declared
        ),
        ));
        capped = true;
    }
    // a mirror image of the source fits clearly better: the clouds are mirror images of each other
    if let Some(m) = mirrored {
        warnings.push(Warning::new(WarningCode::MirrorImage, format!(
            "a mirror image of the source fits the target clearly better than the answer (fitness {:.3}, inlier RMSE {} \
             against {:.3}, {}): one cloud is probably a mirror image of the other (a left part for a right one, a \
             file with one axis flipped), which no rigid motion aligns",
            m.fitness,
            num(m.inlier_rmse * s),
            fitness,
            num(answer.inlier_rmse * s)
        )));
        capped = true;
    }
    // the answer contradicts the caller's guess
    if let Some(turn) = far_from_guess {
        warnings.push(Warning::new(
            WarningCode::TurnedFromGuess,
            format!(
            "the answer turns {turn:.0} degrees away from initialTransform (more than {GUESS_TURN_DEG:.0}): either the \
             guess was off, or the answer is a look-alike that fits about as well (a sparse or partial source turned \
             over); check the guess, or leave it out if it is not one"
        ),
        ));
        capped = true;
    }
    // the surfaces leave a motion free: where the clouds' edges fall is all that holds the answer
    if let Some(m) = free {
        let place = |q: Vector3<f64>| p.in_target_frame(q);
        let (count, keep, that) = match m.count() {
            1 => ("one motion".to_string(), "keeps", "that motion"),
            n => (format!("{n} motions"), "keep", "those motions"),
        };
        warnings.push(Warning::new(
            WarningCode::FreeMotion,
            format!(
                "the fit leaves {count} free: {} {keep} the source on the target's surface (a surface of revolution \
                 about its axis, a straight pipe, tunnel or extrusion along itself, a plane in itself), or nearly (small \
                 features repeated along it: holes on a bolt circle, a gear's teeth), so only where the clouds' edges \
                 fall, or those small features, holds the answer there, and it may be off along {that} \
                 (evidence.constraint {:.1e}; slid along the first by a quarter of the clouds' half-size, the answer \
                 keeps {:.0}% of its fit)",
                m.describe(&place, s),
                m.constraint,
                100.0 * m.slide.min(1.0)
            ),
        ));
        capped = true;
    }
    // a target too sparse for the distance: independent samples seldom pair up, right or wrong
    if let Some((spacings, fitness)) = sparse {
        warnings.push(Warning::new(
            WarningCode::FewPoints,
            format!(
                "the target's points lie {spacings:.1} times the distance the answer is judged at ({}) apart (the \
                 median distance to a point's 4th nearest neighbour), and {:.0}% of the source's fit within it: the \
                 clouds are too sparse for the fit to tell a right pose from a wrong one; give denser clouds (more \
                 points over the same surface)",
                num(p.d_evidence * s),
                100.0 * fitness
            ),
        ));
        capped = true;
    }
    let confidence = if capped { confidence.min(UNREFINED_CONFIDENCE) } else { confidence };
    // a source of few points: a pose judged on so few is as sure as they are many
    // (distinct points: the same ones repeated judge nothing more)
    let n = crate::cloud::distinct_up_to(&p.src_n.points, SURE_POINTS);
    let few = n as f64 / SURE_POINTS as f64;
    if n < SURE_POINTS && confidence > few {
        let count = match p.src_n.len() {
            len if n < len => format!("{n} distinct points (of {len}: the others repeat them)"),
            _ => format!("{n} points"),
        };
        warnings.push(Warning::new(
            WarningCode::FewPoints,
            format!(
                "the source has {count}: an answer judged on fewer than {SURE_POINTS} is at most {few:.2} \
                 sure ({n}/{SURE_POINTS}); give it more points"
            ),
        ));
        return few;
    }
    confidence
}

/// A source of fewer points than this has an answer at most `points / SURE_POINTS` sure: 16 to
/// 24 points cropped from a partial scan came back 16-63 degrees off at 0.93-0.98 in 3 of 8 tries
/// (a junior web developer's trial, `BENCHMARK.md`, session 63); from 32 points on every try was
/// right.
pub(crate) const SURE_POINTS: usize = 64;
