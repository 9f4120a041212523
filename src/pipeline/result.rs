//! Stage 6: the answer in the caller's frame.
//!
//! Takes the [`Prepared`] clouds, the network's estimate and the search's [`Chosen`] answer
//! (normalised units); gives the [`Registration`] in the caller's frame and units: the
//! normalisation, the initial guess's rotation and the clouds' origins undone (for the answer,
//! the network's estimate and the alternative poses; times the `sourceScale`, so that they map the
//! source as given), every transform checked finite, a warning
//! added when the confidence is low or another pose fits as well ([`verdict_warning`]). The
//! timings are the caller's.

use super::prepare::Prepared;
use super::search::Chosen;
use crate::confidence::{Evidence, ScrewPart};
use crate::origin;
use crate::refine::Candidate;
use crate::register::{Alternative, FreeMotion, FreeMotionKind, Registration, Timings};
use crate::warning::{Warning, WarningCode};
use crate::{checks, Result};
use nalgebra::{Matrix4, Vector3};

/// Confidence below which a warning says the alignment may be wrong (as it does whenever another
/// pose fits about as well, which caps the confidence at 0.5).
const LOW_CONFIDENCE: f64 = 0.5;

/// Maps the chosen answer back to the caller (see the module docs).
#[allow(non_snake_case)]
pub(crate) fn finish(
    prepared: &Prepared,
    t_net_n: &Matrix4<f64>,
    chosen: Chosen,
    mut warnings: Vec<Warning>,
    timings: Timings,
) -> Result<Registration> {
    let p = prepared;
    let s = p.norm.scale;
    let d_final = p.d_final;
    let Chosen { candidate, evidence, confidence, starts_refined, alternatives, free } = chosen;
    let Candidate { start, T_target_source: t_n, fitness, inlier_rmse: rmse_n, iterations, converged } = candidate;
    // with `sourceScale` the pipeline's source was the caller's scaled: the answer maps the source as given
    let given = Matrix4::new_nonuniform_scaling(&Vector3::repeat(p.source_scale));
    let to_caller = |t: &Matrix4<f64>| {
        origin::to_caller(&(p.norm.denormalize(t) * p.rotate_init), p.origin_source, p.target.summary.origin) * given
    };
    let T_target_source = to_caller(&t_n);
    let T_target_source_network = to_caller(t_net_n);
    checks::finite_transform(&T_target_source, "the result")?;
    checks::finite_transform(&T_target_source_network, "the network's estimate")?;
    let verdict = verdict_warning(confidence, &evidence, fitness, d_final * s);
    warnings.extend(verdict.map(|m| Warning::new(WarningCode::LowConfidence, m)));
    let mut others = Vec::with_capacity(alternatives.len());
    for a in alternatives {
        let t = to_caller(&a.T_target_source);
        checks::finite_transform(&t, "an alternative pose")?;
        others.push(Alternative { T_target_source: t, fitness: a.fitness, inlier_rmse: a.inlier_rmse * s });
    }
    let free_motions =
        free.map(|f| f.parts().into_iter().map(|part| free_motion(p, part)).collect()).unwrap_or_default();
    let (warning_codes, warnings) = warnings.into_iter().map(|w| (w.code, w.message)).unzip();
    Ok(Registration {
        T_target_source,
        T_target_source_network,
        start,
        fitness,
        inlier_rmse: rmse_n * s,
        icp_iterations: iterations,
        icp_converged: converged,
        max_correspondence_distance: d_final * s,
        timings,
        warnings,
        warning_codes,
        confidence,
        evidence,
        starts_refined,
        alternatives: others,
        free_motions,
    })
}

/// A free motion of the normalised target frame in the caller's target frame: directions as they
/// are (the normalisation neither turns nor mirrors), points placed with the origin.
fn free_motion(p: &Prepared, part: ScrewPart) -> FreeMotion {
    let (kind, direction, through) = match part {
        ScrewPart::Turn { axis, through } => (FreeMotionKind::Turn, axis, through),
        ScrewPart::Slide { direction, at } => (FreeMotionKind::Slide, direction, at),
    };
    FreeMotion { kind, direction: direction.into(), through: p.in_target_frame(through).into() }
}

/// The warning of a doubtful answer: its confidence is below [`LOW_CONFIDENCE`], or another pose
/// fits about as well (`alternatives`, which caps the confidence at 0.5: a coin flip between two
/// poses at best). `fitness` is the answer's within `distance` (the caller's units).
fn verdict_warning(confidence: f64, evidence: &Evidence, fitness: f64, distance: f64) -> Option<String> {
    if confidence >= LOW_CONFIDENCE && evidence.alternatives < 1.0 {
        return None;
    }
    // the evidence of another pose fitting as well, when there is some
    let others = match evidence.alternatives as usize {
        0 => String::new(),
        1 => "; another pose fits about as well (a symmetric or repeating shape?)".to_string(),
        k => format!("; {k} other poses fit about as well (a symmetric or repeating shape?)"),
    };
    Some(format!(
        "low confidence {confidence:.2}: the alignment may be wrong (fitness {fitness:.2} within {}, reverse overlap {:.2}{others})",
        crate::error::num(distance),
        evidence.overlap_reverse
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn evidence(alternatives: f64) -> Evidence {
        Evidence { fitness: 0.4, overlap_reverse: 0.3, alternatives, ..Evidence::default() }
    }

    #[test]
    fn doubtful_answers_are_warned_and_confident_ones_are_not() {
        assert_eq!(verdict_warning(0.93, &evidence(0.0), 0.4, 0.05), None);
        assert_eq!(verdict_warning(0.5, &evidence(0.0), 0.4, 0.05), None);
        let low = verdict_warning(0.3, &evidence(0.0), 0.4, 0.05).unwrap();
        assert!(low.starts_with("low confidence 0.30") && !low.contains("fits about as well"), "{low}");
        // one alternative caps the confidence at exactly 0.5: a coin flip, warned
        let flip = verdict_warning(0.5, &evidence(1.0), 0.4, 0.05).unwrap();
        assert!(flip.contains("another pose fits about as well"), "{flip}");
        let many = verdict_warning(0.25, &evidence(3.0), 0.4, 0.05).unwrap();
        assert!(many.contains("3 other poses fit about as well"), "{many}");
    }
}
