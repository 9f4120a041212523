//! The robust last refinement (`icpLoss: "robust"`, the default): the search's least-squares
//! answer refined once more with the pairs far beyond the spread of the rest (a surface that
//! changed between the scans) weighed down, kept where it puts clearly more of the source on the
//! target's surfaces.

use crate::icp::{IcpKind, IcpParams, IcpTarget};
use crate::refine::{self, Candidate};
use nalgebra::Matrix4;

/// The first fixed biweight scale of [`polish`]'s graduated descent, in final distances; each
/// step halves it.
const GRADUATED_FIRST: f64 = 0.5;

/// Steps of [`polish`]'s graduated descent (scales of a half to a sixteenth of the distance).
/// Least squares lets a changed surface within the distance (a fill pad over a quarter of a
/// survey, 1-2 m at 1.8 m) tilt the answer so far that every residual spreads, and a robust run at
/// the spread's scale stays near the tilt; fixed scales, halving, leave the changed surface out
/// first and come back to the rest (`BENCHMARK.md`, "Changed scenes: the robust loss from the
/// guess on, a graduated descent, and the default"). A fifth step or a first scale at the
/// distance itself changed nothing measured.
const GRADUATED_STEPS: u32 = 4;

/// [`polish`] keeps a robust pose only when this many times as many of the source's points lie
/// on the target's surfaces ([`NOISE_TIMES`]) as under the least-squares answer (and its descent's
/// pose only when this many times as many as under the pose refined at the spread's scale alone):
/// where nothing changed the answer stays least squares' (on 1,100 validation pairs 4-13 in 300
/// changed, about as many better as worse; the real scans all kept, 2 of 12 LiDAR pairs closer).
const GAIN: f64 = 1.05;

/// [`polish`] judges its poses by the share of the source within this many times the noise of
/// the target's surfaces (along their normals, [`IcpTarget::plane_residuals`]), the noise being
/// the smallest of the poses' median residuals: a changed surface lies beyond, however high it
/// is against the distance or the target's spacing (a 0.5-1.5 m pad at a distance of several
/// metres, on a target voxelised coarser than a metre).
const NOISE_TIMES: f64 = 3.0;

/// `answer` refined by ICP at the final distance `d` with Tukey's biweight on its pairs
/// ([`IcpParams::robust`]), on at most [`refine::REFINE_POINTS`] of the source's points: at the
/// biweight scale of the pairs' spread, and by a graduated descent (fixed scales from
/// [`GRADUATED_FIRST`] of `d`, halving, [`GRADUATED_STEPS`] times, then the spread's again) from
/// the answer and, with the caller's `guess`, from the guess too; the best of them by the share of
/// the sample on the target's surfaces ([`NOISE_TIMES`], [`GAIN`]) replaces `answer` when it puts
/// clearly more there, with its fitness measured on all of the source at `d`; else `answer` as it
/// is.
pub(super) fn polish(
    target: &IcpTarget,
    source: &[[f32; 3]],
    answer: &Candidate,
    guess: Option<&Matrix4<f64>>,
    kind: IcpKind,
    d: f64,
    max_iterations: u32,
) -> Candidate {
    let sample = refine::even_sample(source, refine::REFINE_POINTS);
    let params = IcpParams { robust: true, max_iterations: max_iterations.max(1) * 2, ..IcpParams::new(kind, d) };
    let graduated = |from: &Matrix4<f64>| {
        let mut t = *from;
        let mut scale = GRADUATED_FIRST * d;
        for _ in 0..GRADUATED_STEPS {
            let fixed = IcpParams { robust_scale: Some(scale), max_iterations: max_iterations.max(1), ..params };
            t = target.align(&sample, &t, &fixed).T_target_source;
            scale *= 0.5;
        }
        target.align(&sample, &t, &params)
    };
    // the spread's run and the descent from the answer, and the descent from the caller's guess
    // (a change that tilted the refinement of a right guess, lower than the tilt's own error, is
    // told from the rest only near the guess)
    let mut runs = vec![target.align(&sample, &answer.T_target_source, &params), graduated(&answer.T_target_source)];
    runs.extend(guess.map(graduated));
    // each pose's share of the sample on the target's surfaces, to within a few times the
    // smallest of their median residuals (the noise, where a pose is right); the answer's first
    let mut residuals: Vec<Vec<f64>> = std::iter::once(&answer.T_target_source)
        .chain(runs.iter().map(|r| &r.T_target_source))
        .map(|t| target.plane_residuals(&sample, t, d))
        .collect();
    let noise = residuals.iter_mut().filter_map(|r| crate::stats::median(r)).fold(f64::INFINITY, f64::min);
    let on = |r: &Vec<f64>| r.iter().filter(|&&x| x <= NOISE_TIMES * noise).count() as f64;
    // the spread's run, unless a descent puts clearly more on the surfaces
    let (mut r, mut on_r) = (&runs[0], on(&residuals[1]));
    for (next, on_next) in runs.iter().zip(residuals[1..].iter().map(on)).skip(1) {
        if on_next > GAIN * on_r {
            (r, on_r) = (next, on_next);
        }
    }
    if on_r <= GAIN * on(&residuals[0]) {
        return *answer;
    }
    let (fitness, inlier_rmse) = target.evaluate(source, &r.T_target_source, d);
    Candidate {
        T_target_source: r.T_target_source,
        fitness,
        inlier_rmse,
        iterations: answer.iterations + r.iterations,
        converged: r.converged,
        ..*answer
    }
}
