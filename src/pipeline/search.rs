//! Stage 5: the search over the starts.
//!
//! Takes the [`Prepared`] clouds, the stages of [`super::starts`] and the options; gives
//! [`Chosen`]: the best refined start ([`refine::refine_best`], compared across stages by
//! [`refine::choose`]) with its [`Evidence`] and confidence. [`Search::Adaptive`] stops after the
//! first stage whose best reaches [`STOP_CONFIDENCE`] (when either cloud has at least
//! [`GLOBAL_BEFORE_STOP_POINTS`] points, not before the global stage has run); when none does, it
//! runs a last stage of blind starts ([`Starts::more`]: more global hypotheses, and the rotations
//! unless the options name the network's turns, [`Start::RotationsNetwork`]), shortlisted to
//! [`LAST_STAGE_STARTS`] ([`refine::shortlist`]), whose best must fit clearly better
//! ([`refine::clearly_better`]). An answer still below [`UNSURE_CONFIDENCE`] after that gets the
//! stage of starts for unsure answers ([`Start::is_for_unsure`], when the options name them), whose
//! best replaces it only when it fits much better ([`UNSURE_GAIN`]). An answer that reaches
//! [`NEARLY_SURE_CONFIDENCE`] once the global stage has run, or [`AGREED_CONFIDENCE`] when the
//! global stage's best is that same pose again, skips the stages left and the rotations: its last
//! stage is the best
//! [`NEARLY_SURE_LAST_STAGE_STARTS`] of the further global hypotheses, of those whose short run
//! comes near the answer's own ([`NEARLY_SURE_SCREEN_FIT`]). The global stage refines, of its
//! hypotheses, the one that fits best after a short run, and those whose short run comes near the
//! answer's so far ([`GLOBAL_SCREEN_FIT`]). Each stage's best, when it
//! is better than the answer so far and another pose ([`refine::coincide`]), is judged by the
//! confidence probe, and a probe pose that fits better is refined as one more start ([`settle`]);
//! while the answer is below [`STOP_CONFIDENCE`], a stage's best that does not replace it is judged
//! too (its probe may find a pose that does: the truth, turned over from it). On clouds of
//! [`GLOBAL_BEFORE_STOP_POINTS`] points the search cannot stop before its global stage, so the best
//! of the stages before it waits unjudged, and the probe judges the better of it and the global
//! stage's best once that stage has run (the other too while the answer is below
//! [`STOP_CONFIDENCE`]). The answer's final verdict also counts, as alternatives, the other refined
//! answers that fit about as well ([`confidence::count_search_alternatives`]); those alternative
//! poses are refined like the answer and handed on with it ([`refine_alternatives`]), and one
//! that then leaves far less of the source off the target ([`refine::leaves_far_less_off`])
//! becomes the answer, judged anew. With `up`
//! ([`Prepared::upright`]), every start is levelled first, a stage whose best ends tilted settles
//! nothing, and the probes count only upright poses (turning the answer about up too). Once the
//! global stage has run, the answer's rotation with the translation its descriptor matches agree
//! on ([`Starts::voted_pose`]: an answer slid along a wall, or onto the next of a row of alike
//! parts, has the rotation right and the translation not) is refined like one more start, and
//! replaces the answer when it fits clearly better; with `up`, so are its quarter and half turns
//! about up ([`UP_TURNS_VOTED`]), each with the translation the matches agree on for it. Then the
//! answer moved onto the other faces of the thin walls the source lies on
//! ([`wall::other_faces`]) is refined at the final distance (where it lands somewhere new:
//! [`refine::refine_final_screened`]), replacing the answer when it fits
//! better ([`wall::fits_better`]) and moved again (up to [`wall::ROUNDS`] times), with a warning
//! when it fits alike ([`wall::fits_alike`]).
//! With no start refined at all, the network's estimate (the initial transform with the network
//! off), unrefined, with a warning and its confidence at most [`caps::UNREFINED_CONFIDENCE`].
//! With `sourceOverlap`, an answer under which clearly less of the source lies on the target than
//! that share counts as unsure at every stage ([`caps::within_overlap`]), so the search goes on
//! past it.

use super::caps;
use super::mirror;
use super::prepare::Prepared;
use super::robust;
use super::starts::{self, Starts, Step};
use super::wall;
use crate::confidence::{self, Evidence, Probed};
use crate::icp::{IcpKind, IcpTarget};
use crate::model::{Model, ModelWorkspace};
use crate::refine::{self, Candidate, Refinement, Start};
use crate::register::{
    Options, Search, AGREED_CONFIDENCE, GLOBAL_BEFORE_STOP_POINTS, GUESS_TURN_DEG, NEARLY_SURE_CONFIDENCE,
    STOP_CONFIDENCE, UNSURE_CONFIDENCE, UP_TOLERANCE_DEG,
};
use crate::warning::{Warning, WarningCode};
use crate::Result;
use nalgebra::{Matrix4, Point3};

/// The answer of the search, in normalised units.
pub(crate) struct Chosen {
    /// The chosen refined start.
    pub candidate: Candidate,
    /// What its confidence is computed from.
    pub evidence: Evidence,
    /// Its confidence.
    pub confidence: f64,
    /// How many starts were refined.
    pub starts_refined: usize,
    /// Other poses that fit about as well ([`Evidence::alternatives`]), refined like the answer,
    /// the best fitting first.
    pub alternatives: Vec<Candidate>,
    /// The motions the fit leaves free ([`Probed::free`]).
    pub free: Option<confidence::FreeScrew>,
}

/// Refines the starts of each stage in turn (see the module docs).
pub(crate) fn search(
    prepared: &Prepared,
    stages: &[Step],
    builder: &mut Starts,
    options: &Options,
    model: &Model,
    workspace: &mut ModelWorkspace,
    warnings: &mut Vec<Warning>,
) -> Result<Chosen> {
    let p = prepared;
    let d_final = p.d_final;
    // normals are estimated as ICP first needs them (only near the source's sampled points)
    let target_index = p.target.index();
    // the network's estimate, or with the network off the initial transform (`starts::kinds`)
    let estimate = if options.network { Start::Network } else { Start::Initial };
    // the local search reaches only as far as the caller's distance: its stages start at a few
    // times it (the others from the default distance, so that the starts travel as far)
    let d_coarse = match options.search {
        Search::Local => d_final,
        _ => super::options::coarse_distance(d_final),
    };
    let how = Refinement {
        estimate: Some(estimate),
        robust_guess: options.icp_loss == crate::icp::IcpLoss::Robust && options.initial_transform.is_some(),
        ..Refinement::new(p.icp, d_final, d_coarse, options.icp_max_iterations)
    };
    let source_index = IcpTarget::new(&p.icp_src.points, false);
    // with `up`: every start levelled, and only upright answers, probe poses and alternatives
    let upright = p.upright;
    let tilt_deg = |t: &Matrix4<f64>| upright.map_or(0.0, |u| u.tilt_deg(t));
    let admissible = match &upright {
        Some(u) => confidence::Admissible::Upright { up: u.up().into_inner(), tilt_deg: &tilt_deg },
        None => confidence::Admissible::Any,
    };
    let admits = |t: &Matrix4<f64>| admissible.admits(t);
    let centroid = p.src_n.centroid();
    let level = |t: Matrix4<f64>| match &upright {
        Some(u) => u.level(&t, &t.transform_point(&Point3::from(centroid)).coords),
        None => t,
    };
    let judge = |t: &Matrix4<f64>| {
        confidence::probe(target_index, &source_index, &p.icp_src.points, t, p.d_evidence, p.icp, &admissible)
    };
    // `c` is a better answer than `b`: it fits better (`refine::better`) and is another pose. A
    // start that only found the answer again (a hair better, perhaps) leaves it as it was judged:
    // probing the same pose again would say the same.
    let improves = |b: &Candidate, c: &Candidate| {
        refine::better(c, b) && !refine::coincide(&b.T_target_source, &c.T_target_source, &p.icp_src.points, d_final)
    };
    // every stage's best and every refined probe pose: the final verdict counts those that fit
    // about as well as the answer as its alternatives
    let mut refined: Vec<(Matrix4<f64>, f64)> = Vec::new();
    // one more pose `t` refined like a start (levelled, reported as `start`), kept only when it
    // ends upright and noted among the refined answers: a probe's better pose, or the answer's
    // voted translation
    let refine_one = |start: Start, t: Matrix4<f64>, refined: &mut Vec<(Matrix4<f64>, f64)>| {
        let r = refine::refine_best(target_index, &p.icp_src.points, &[(start, level(t))], &how)
            .filter(|r| admits(&r.T_target_source));
        refined.extend(r.map(|r| (r.T_target_source, r.fitness)));
        r
    };
    // one more pose `t` (levelled) refined at the final distance only where it lands somewhere
    // new (the next of a row of alike parts; `refine::refine_final_screened`), kept as
    // `refine_one` keeps its poses
    let capped = refine::even_sample(&p.icp_src.points, refine::REFINE_POINTS);
    let screen = refine::even_sample(&p.icp_src.points, refine::SCREEN_POINTS);
    // most pairs' matches scatter into a second cluster by chance: a pose that does not already
    // fit half as well as the answer is not refined
    let next_fits =
        |c: &Candidate, t: &Matrix4<f64>| target_index.evaluate(&screen, t, d_final).0 >= NEXT_PART_SCREEN * c.fitness;
    // with a final distance wider than the default (the caller's), fitness there makes every pose
    // fit (a correct answer's flip about an axis 0.93 as well as the answer at ten times the
    // default): the verdict compares the answer and the refined poses at the evidence distance,
    // where the probes compare theirs
    let at_evidence =
        (p.d_evidence < d_final).then_some(|t: &Matrix4<f64>| target_index.evaluate(&capped, t, p.d_evidence).0);
    let next_part = |c: &Candidate, t: Matrix4<f64>, refined: &mut Vec<(Matrix4<f64>, f64)>| {
        let r = refine::refine_final_screened(target_index, &capped, c.start, &t, &how, &c.T_target_source);
        let r = r.filter(|r| admits(&r.T_target_source));
        refined.extend(r.map(|r| (r.T_target_source, r.fitness)));
        r
    };
    // `c` judged by the probe, and the probe's better poses refined ([`settle`]): the answer with
    // its evidence and confidence, and how many probe poses were refined
    let judged = |c: Candidate, refined: &mut Vec<(Matrix4<f64>, f64)>| {
        // with ICP off the first start is the answer, unrefined: the probe only judges it
        let (c, probed, extra) = if p.icp == IcpKind::Off {
            (c, judge(&c.T_target_source), 0)
        } else if options.search == Search::Local {
            // the local search keeps its answer: a better pose of the probe is refined and noted
            // among the refined answers (an alternative), not taken
            let probed = judge(&c.T_target_source);
            let extra = probed.better.map_or(0, |t| {
                refine_one(c.start, t, refined);
                1
            });
            (c, probed, extra)
        } else {
            settle(c, &judge, |t| refine_one(c.start, t, refined), &improves)
        };
        let confidence =
            caps::within_overlap(confidence::confidence(&probed.evidence), &probed.evidence, options.source_overlap);
        ((c, probed, confidence), extra)
    };
    // the answer so far, judged; and a better one that waits for the global stage unjudged
    // (see `waits` below)
    let mut best: Option<(Candidate, Probed, f64)> = None;
    let mut waiting: Option<Candidate> = None;
    let mut starts_refined = 0usize;
    // with `up`: the best stage answer that ended tilted, which settles nothing but, fitting
    // clearly better than the upright answer, says that `up` may not hold
    let mut tilted: Option<Candidate> = None;
    let adaptive = options.search == Search::Adaptive;
    let kinds = starts::kinds(options);
    let has_global = kinds.iter().any(|k| k.is_global());
    let many_points = p.src_n.len().max(p.target.cloud.len()) >= GLOBAL_BEFORE_STOP_POINTS;
    let mut reached_global = false;
    // once the global stage had run, the answer reached NEARLY_SURE_CONFIDENCE, or
    // AGREED_CONFIDENCE with the global stage finding it again
    let mut nearly_sure = false;
    for step in stages {
        let global_stage = matches!(step, Step::Listed(s) if s.iter().any(|k| k.is_global()));
        // on clouds of many points the search cannot stop before its global stage: the best of
        // the stages before it waits, unjudged, and the probe judges it or the global stage's
        // better answer once that stage has run (a wrong network start, which the probe would
        // have turned over, is then usually beaten by a global hypothesis first)
        let waits = adaptive
            && many_points
            && has_global
            && !reached_global
            && !global_stage
            && p.icp != IcpKind::Off
            && matches!(step, Step::Listed(_));
        if !matches!(step, Step::Listed(_)) {
            if let Some(w) = waiting.take() {
                let (b, extra) = judged(w, &mut refined);
                (best, starts_refined) = (Some(b), starts_refined + extra);
            }
        }
        let mut starts = match step {
            Step::Listed(_) if nearly_sure => continue,
            Step::Listed(stage) => {
                // the adaptive search describes a pair between sparse and dense finer too only
                // when the answer so far leaves more than half of the source off the target
                if global_stage && adaptive {
                    let so_far = waiting.or(best.as_ref().map(|b| b.0));
                    builder.finer = so_far.is_none_or(|c| c.fitness < FINER_BELOW_FITNESS);
                }
                let starts = builder.build(stage, model, workspace)?;
                // the global hypotheses, against the answer so far: the best, and those that come
                // near its fit
                match waiting.or(best.as_ref().map(|b| b.0)) {
                    Some(so_far) if global_stage && adaptive && p.icp != IcpKind::Off => {
                        let screen = refine::Screen {
                            T_target_source: &so_far.T_target_source,
                            fit: GLOBAL_SCREEN_FIT,
                            keep_best: 1,
                        };
                        let all = starts.len();
                        refine::shortlist(target_index, &p.icp_src.points, starts, &how, all, Some(screen))
                    }
                    _ => starts,
                }
            }
            // no stage stopped the search (the loop breaks at STOP_CONFIDENCE)
            Step::Blind if adaptive && p.icp != IcpKind::Off && best.is_some() => {
                // blind starts, most of which land nowhere: a short run each picks those refined
                let rotations = starts::blind_rotations(&kinds, nearly_sure);
                let more = builder.more(&kinds, rotations, model, workspace)?;
                let keep = if nearly_sure { NEARLY_SURE_LAST_STAGE_STARTS } else { LAST_STAGE_STARTS };
                // a nearly sure answer's last stage: only starts that come near its fit
                let screen = best.as_ref().filter(|_| nearly_sure).map(|b| refine::Screen {
                    T_target_source: &b.0.T_target_source,
                    fit: NEARLY_SURE_SCREEN_FIT,
                    keep_best: 0,
                });
                refine::shortlist(target_index, &p.icp_src.points, more, &how, keep, screen)
            }
            Step::Blind => continue,
            // judged as the caller would see it: with the look-alikes the search found so far
            Step::Unsure(_)
                if adaptive
                    && best.as_ref().is_some_and(|(c, probed, _)| {
                        verdict(c, None, probed, &refined, at_evidence.as_ref()).2 >= UNSURE_CONFIDENCE
                    }) =>
            {
                continue
            }
            Step::Unsure(stage) => builder.build(stage, model, workspace)?,
        };
        if p.icp == IcpKind::Off {
            // nothing is refined or compared: the first start is the answer
            starts.truncate(1);
        }
        for (_, t) in &mut starts {
            *t = level(*t);
        }
        if starts.is_empty() {
            continue;
        }
        starts_refined += starts.len();
        let Some(c) = refine::refine_best(target_index, &p.icp_src.points, &starts, &how) else { continue };
        // (with `up`, a stage whose best refined start ended tilted settles nothing)
        if !admits(&c.T_target_source) {
            if tilted.as_ref().is_none_or(|t| c.fitness > t.fitness) {
                tilted = Some(c);
            }
            continue;
        }
        refined.push((c.T_target_source, c.fitness));
        // the answer so far, judged or waiting
        let so_far = waiting.or(best.as_ref().map(|b| b.0));
        // the global stage found the answer again: the descriptors' hypotheses, independent of
        // the network and of the local starts, agree with it
        let agrees = global_stage
            && so_far
                .is_some_and(|b| refine::coincide(&b.T_target_source, &c.T_target_source, &p.icp_src.points, d_final));
        // `c` of this stage replaces the answer `b`
        let beats = |b: &Candidate, c: &Candidate| match step {
            // the last stage's starts are blind: a near tie stays with the answer
            Step::Blind => refine::clearly_better(c, b) && improves(b, c),
            // the network's turns search every orientation, whatever the initial guess: only a
            // much better fit is another pose than a look-alike
            Step::Unsure(_) => improves(b, c) && c.fitness > b.fitness * (1.0 + UNSURE_GAIN),
            Step::Listed(_) => improves(b, c),
        };
        let better = so_far.as_ref().is_none_or(|b| beats(b, &c));
        // the contender this stage passes over: the waiting answer that its best beats, or the
        // best that the answer beats
        let passed_over = match waiting {
            Some(w) if better => Some(w),
            _ if better => None,
            _ => Some(c),
        };
        if better {
            waiting = Some(c);
        }
        if !waits {
            if let Some(w) = waiting.take() {
                let (b, extra) = judged(w, &mut refined);
                (best, starts_refined) = (Some(b), starts_refined + extra);
            }
            // an answer the search is unsure of: the contender passed over is judged too, since
            // its probe may find a pose that beats the answer (typically the contender turned
            // over onto the truth)
            let unsure_of = |o: &Candidate| {
                best.as_ref().is_some_and(|b| {
                    b.2 < STOP_CONFIDENCE
                        && !refine::coincide(&o.T_target_source, &b.0.T_target_source, &p.icp_src.points, d_final)
                })
            };
            if let Some(o) = passed_over.filter(unsure_of) {
                let (other, extra) = judged(o, &mut refined);
                starts_refined += extra;
                if best.as_ref().is_some_and(|b| beats(&b.0, &other.0)) {
                    best = Some(other);
                }
            }
        }
        reached_global |= global_stage;
        // on clouds of many points the confidence is measured to be too sure of wrong answers
        // (it was calibrated on sparse, noisy pairs): a confident answer stops the search only
        // once the global stage has run
        let stop = adaptive
            && best.as_ref().is_some_and(|b| b.2 >= STOP_CONFIDENCE)
            && (reached_global || !has_global || !many_points);
        if stop {
            break;
        }
        // nearly sure after the global stage (or not flagged, and found again by it): the other
        // stages are skipped, and the last one draws only a few more global hypotheses
        let sure_enough =
            |b: &(Candidate, Probed, f64)| b.2 >= NEARLY_SURE_CONFIDENCE || (agrees && b.2 >= AGREED_CONFIDENCE);
        nearly_sure |= adaptive && reached_global && best.as_ref().is_some_and(sure_enough);
    }
    if let Some(w) = waiting.take() {
        let (b, extra) = judged(w, &mut refined);
        (best, starts_refined) = (Some(b), starts_refined + extra);
    }
    // poses placed where the global stage's matches agree for a rotation, each refined like one
    // more start, noted among the refined answers (an alternative when it fits about as well)
    // and replacing the answer when it fits clearly better: the answer's own rotation (a slid
    // answer, its rotation right and its translation not: a wall matched to the next one) and,
    // with `up`, the answer turned a quarter and a half turn about up (a box-like room captured
    // from another spot fits its turns about as well as the truth, and the probes, which turn
    // the answer about its own centre, cannot move it that far); and the answer's rotation at
    // the next translation the matches agree on, refined at the final distance only (the next
    // of a row of alike parts, such as two identical pipe spools side by side: the wider stages
    // would pull it back onto the part the answer is on)
    let placed: Vec<(Matrix4<f64>, bool)> = match &best {
        Some((c, _, _)) if adaptive && p.icp != IcpKind::Off => {
            let t = &c.T_target_source;
            let pivot = t.transform_point(&Point3::from(centroid)).coords;
            let turned = upright.iter().flat_map(|u| UP_TURNS_VOTED.map(|deg| u.turned(t, deg, &pivot)));
            let own = builder.voted_poses(t, VOTED_MODES).into_iter().map(|(r, rank)| (r, rank > 0));
            let turned = turned.filter_map(|r| builder.voted_pose(&r)).map(|r| (r, false));
            own.chain(turned).collect()
        }
        _ => Vec::new(),
    };
    for (t, final_only) in placed {
        let Some(c) = best.as_ref().map(|b| b.0) else { break };
        // (levelled once: screened and refined from the same pose; `refine_one` levels its own)
        let next = final_only.then(|| level(t));
        if next.is_some_and(|t| !next_fits(&c, &t)) {
            continue;
        }
        starts_refined += 1;
        let r = match next {
            Some(t) => next_part(&c, t, &mut refined),
            None => refine_one(c.start, t, &mut refined),
        };
        if let Some(r) = r {
            if refine::clearly_better(&r, &c) && improves(&c, &r) {
                let (b, extra) = judged(r, &mut refined);
                (best, starts_refined) = (Some(b), starts_refined + extra);
            }
        }
    }
    // the answer moved onto the other faces of the thin walls the source lies on: one that fits
    // better replaces it; one that fits alike is said in a warning
    if let Some((c, _, _)) = best.as_ref().filter(|_| adaptive && p.icp != IcpKind::Off) {
        let start = *c;
        let moved = wall::across_walls(
            target_index,
            &p.icp_src.points,
            start,
            &how,
            &level,
            &admits,
            &improves,
            (centroid.into(), p.norm.scale),
        );
        starts_refined += moved.tried;
        refined.extend(moved.refined.iter().map(|r| (r.T_target_source, r.fitness)));
        warnings.extend(moved.warning);
        if moved.chosen.T_target_source != start.T_target_source {
            let (b, extra) = judged(moved.chosen, &mut refined);
            (best, starts_refined) = (Some(b), starts_refined + extra);
        }
    }
    // no start at all (only global ones, and the descriptors matched too little): the first
    // start the options name, unrefined
    let (candidate, probed, refined_any) = match best {
        Some((c, probed, _)) => (c, probed, true),
        None => {
            let t = level(if options.network { builder.t_net_n() } else { p.t_initial });
            let probed = judge(&t);
            let answer = if options.network { "the network's estimate" } else { "the initial transform" };
            warnings.push(Warning::new(WarningCode::Unrefined, match upright {
                Some(_) => format!("no refined start ended upright (within {UP_TOLERANCE_DEG} degrees of `up`), or the global descriptors matched too little: the answer is {answer}, levelled, unrefined"),
                None => format!("no start could be refined (the global descriptors matched too little): the answer is {answer}, unrefined"),
            }));
            // its fitness at the final distance, as every answer's (the evidence's may be tighter)
            let (fitness, inlier_rmse) = target_index.evaluate(&p.icp_src.points, &t, d_final);
            let c = Candidate {
                start: estimate,
                T_target_source: t,
                fitness,
                inlier_rmse,
                iterations: 0,
                converged: false,
            };
            (c, probed, false)
        }
    };
    // with `icpLoss: "robust"` (the default): the answer refined once more with the pairs far
    // beyond the spread of the rest (a surface that changed between the scans) weighed down,
    // and judged there when that puts clearly more of the source on the target; its look-alikes
    // still count as against the least-squares answer (`verdict`)
    let mut polished_from = None;
    let guess = options.initial_transform.is_some().then_some(&p.t_initial);
    let (candidate, probed) =
        match refined_any && p.icp != IcpKind::Off && options.icp_loss == crate::icp::IcpLoss::Robust {
            true => {
                let c = robust::polish(
                    target_index,
                    &p.icp_src.points,
                    &candidate,
                    guess,
                    p.icp,
                    d_final,
                    options.icp_max_iterations,
                );
                let c = if admits(&c.T_target_source) { c } else { candidate };
                if c.T_target_source == candidate.T_target_source {
                    (c, probed)
                } else {
                    polished_from = Some(candidate);
                    (c, judge(&c.T_target_source))
                }
            }
            false => (candidate, probed),
        };
    // The motions the fit leaves free, as the probe measured them from the target's normals; none
    // on a target too sparse for the distance, whose normals, estimated from points many
    // distances apart, are not a surface's (a set of distinct markers pins every motion; 20-33
    // survey corners were said to leave three free)
    let sparse_target = caps::sparse_spacings(target_index, p.d_evidence);
    let free_of = |probed: &Probed| probed.free.filter(|_| sparse_target.is_none());
    // with the caller's guess: along a motion the surfaces leave free (a jar's turn about its axis
    // on a turntable: `constraint` below the line), where only the clouds' edges held the answer,
    // the guess says where it is. Along a motion the fit only barely holds (`slide`) only when the
    // answer turned far from the guess (a nearly round teapot: 25-30 degrees from a guess 1 degree
    // off): a low relief pins the pose by its gentle slopes, which ICP follows from a near guess to
    // the truth, though a slid pose keeps most of the fit at the default distance (a 30 mm
    // bas-relief, 4.5 mm: held at a 2-degree guess's error; 0.004 degrees without the hold)
    let surfaces_free = |f: &confidence::FreeScrew| f.constraint < confidence::UNPINNED_CONSTRAINT;
    let turned_far =
        crate::transform::rotation_error_deg(&candidate.T_target_source, &p.t_initial) > HELD_SLID_TURN_DEG;
    let guided = refined_any && options.initial_transform.is_some();
    // (the motion an answer was held along: still the one the result names, when the probe of
    // the held pose finds it held a little more firmly there)
    let mut held_along = None;
    let (mut candidate, mut probed) = match free_of(&probed).filter(|f| guided && (surfaces_free(f) || turned_far)) {
        Some(free) => {
            match held_by_guess(&free, !surfaces_free(&free), &candidate, p, target_index, &screen, &admits) {
                Some((held, why)) => {
                    warnings.push(Warning::new(WarningCode::HeldByGuess, why));
                    held_along = Some(free);
                    let probed = judge(&held.T_target_source);
                    (held, probed)
                }
                None => (candidate, probed),
            }
        }
        None => (candidate, probed),
    };
    let versus = polished_from.filter(|_| held_along.is_none());
    let (mut evidence, mut poses, mut confidence) =
        verdict(&candidate, versus.as_ref(), &probed, &refined, at_evidence.as_ref());
    let mut alternatives = refine_alternatives(target_index, &p.icp_src.points, &candidate, &poses, &how);
    // an alternative that, refined like the answer, leaves far less of the source off the
    // target (a scan inside its model: the answer a gear turned over, its keyway off the model,
    // where the probes found the truth) is the answer, judged anew, and the answer one of its
    // alternatives; one that fits only somewhat better stays an alternative (on the validation
    // pairs, a tenth better turned a near-symmetric trim the wrong way over)
    let swap = refined_any && p.icp != IcpKind::Off && options.search != Search::Local && held_along.is_none();
    let beats = |a: &Candidate| {
        refine::leaves_far_less_off(a, &candidate)
            && !refine::coincide(&candidate.T_target_source, &a.T_target_source, &p.icp_src.points, d_final)
            && admits(&a.T_target_source)
    };
    if let Some(a) = alternatives.iter().find(|a| swap && beats(a)) {
        let a = *a;
        refined.push((candidate.T_target_source, candidate.fitness));
        (candidate, probed) = (a, judge(&a.T_target_source));
        (evidence, poses, confidence) = verdict(&candidate, None, &probed, &refined, at_evidence.as_ref());
        alternatives = refine_alternatives(target_index, &p.icp_src.points, &candidate, &poses, &how);
    }
    let apart = |a: &Matrix4<f64>, b: &Matrix4<f64>| apart(a, b, centroid);
    // the local search kept its answer where a pose the probes found fits better
    if options.search == Search::Local {
        let t = &candidate.T_target_source;
        let elsewhere = refined
            .iter()
            .filter(|(o, f)| *f > candidate.fitness && !confidence::same_pose(o, t))
            .max_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((o, f)) = elsewhere {
            warnings.push(Warning::new(
                WarningCode::BetterPoseNotTaken,
                format!(
                    "a pose {:.1} degrees from the answer, putting the source {} from where the answer puts it, fits \
                     better (fitness {:.2} against {:.2}; among the alternatives): the local search keeps the answer \
                     its starts refined to",
                    crate::transform::rotation_error_deg(o, t),
                    crate::error::num(apart(o, t) * p.norm.scale),
                    f,
                    candidate.fitness
                ),
            ));
        }
    }
    // with `up`: a tilted pose that fits clearly better than the upright answer
    let tilted = tilted
        .filter(|t| refined_any && refine::clearly_better(t, &candidate))
        .map(|t| caps::Tilted { tilt_deg: tilt_deg(&t.T_target_source), fitness: t.fitness });
    let short = caps::short_of_overlap(&evidence, options.source_overlap);
    // with `sourceOverlap` (a scan onto its model, where a mirrored part or export is a common
    // mistake): a mirror image of the source that fits clearly better
    let mirrored = (refined_any && p.icp != IcpKind::Off && options.source_overlap.is_some())
        .then(|| mirror::fits_better(target_index, &p.icp_src.points, &candidate, &how, &admits))
        .flatten();
    // with the caller's guess: an answer that turns far from it
    let turn = crate::transform::rotation_error_deg(&candidate.T_target_source, &p.t_initial);
    let far_from_guess = (options.initial_transform.is_some() && turn > GUESS_TURN_DEG).then_some(turn);
    // ... or that puts the source farther from where the guess puts it than half the source's
    // size (`GUESS_SHIFT`): a look-alike elsewhere (a repeated room, the next bay) when the guess
    // placed it
    if options.initial_transform.is_some() {
        let shift = apart(&candidate.T_target_source, &p.t_initial);
        let size = p.src_n.half_extent();
        if shift > GUESS_SHIFT * size {
            warnings.push(Warning::new(WarningCode::FarFromGuess, format!(
                "the answer puts the source {} from where initialTransform puts it, {:.1} times the source's half-extent: \
                 if the guess placed it, the answer may be a look-alike elsewhere (a repeated room, the next bay)",
                crate::error::num(shift * p.norm.scale),
                shift / size
            )));
        }
    }
    let free = free_of(&probed).or(held_along);
    let sparse = caps::too_sparse(sparse_target, evidence.fitness);
    let doubts = caps::Doubts { refined_any, tilted, short, mirrored, far_from_guess, free, sparse };
    let confidence = caps::cap(p, confidence, &candidate, doubts, warnings);
    // a refinement of the caller's guess alone that ended at another pose (ICP went far, or the
    // probes turned it over), not so far as to contradict it: the caller asked to refine that
    // guess, so the result says how far it moved
    if options.initial_transform.is_some()
        && kinds == [Start::Initial]
        && refined_any
        && far_from_guess.is_none()
        && !confidence::same_pose(&candidate.T_target_source, &p.t_initial)
    {
        warnings.push(Warning::new(WarningCode::TurnedFromGuess, format!(
            "the answer turns {turn:.1} degrees from initialTransform, the one start: ICP from it, or a pose the \
             confidence's probes turned it to, fit better there (a guess that was off, or a symmetric shape's look-alike)"
        )));
    }
    Ok(Chosen { candidate, evidence, confidence, starts_refined, alternatives, free })
}

/// With [`Options::initial_transform`], an answer that puts the source's centroid farther than
/// this fraction of the source's largest half-extent from where the guess puts it gets a warning
/// (no cap: a guess may give the rotation alone). A BIM user's scan of two rooms and a corridor,
/// placed on the plan 30 degrees and 1.4 m off, came back in the identical rooms 8.8 m away (0.65
/// of its half-extent) at 0.996 without a word.
const GUESS_SHIFT: f64 = 0.5;

/// The final verdict on the answer `c` judged by the probe (`probed`): its evidence, with the
/// other answers the search `refined` that fit about as well counted as alternatives
/// ([`confidence::count_search_alternatives`]), those alternative poses, and its confidence. With
/// `at_evidence` (a final distance wider than the evidence distance), the answer and the refined
/// poses are compared by their fitness at the evidence distance, not at the final one.
/// With `polished_from` (the least-squares answer that the robust refinement replaced by `c`),
/// the refined poses count against the lesser of the two fits: they were refined by least
/// squares, and a polish that puts more of the source on the target does not make the
/// look-alikes the search found fit less alike (a cone 64 degrees off, whose one look-alike
/// went at 0.5 to none at 0.81).
fn verdict(
    c: &Candidate,
    polished_from: Option<&Candidate>,
    probed: &Probed,
    refined: &[(Matrix4<f64>, f64)],
    at_evidence: Option<&impl Fn(&Matrix4<f64>) -> f64>,
) -> (Evidence, Vec<Matrix4<f64>>, f64) {
    let (mut evidence, mut poses) = (probed.evidence, probed.alternatives.clone());
    let remeasured: Vec<(Matrix4<f64>, f64)>;
    let (fitness, refined) = match at_evidence {
        Some(fit) => {
            remeasured = refined.iter().map(|(t, _)| (*t, fit(t))).collect();
            let of = |c: &Candidate| fit(&c.T_target_source);
            (of(c).min(polished_from.map_or(f64::INFINITY, of)), remeasured.as_slice())
        }
        None => (c.fitness.min(polished_from.map_or(f64::INFINITY, |u| u.fitness)), refined),
    };
    confidence::count_search_alternatives(&mut evidence, &mut poses, &c.T_target_source, fitness, refined);
    (evidence, poses, confidence::confidence(&evidence))
}

/// The alternative `poses` of the answer refined like it ([`refine::refine_final`] on the source
/// capped as for the answer, reported under its start), the best fitting first; one that the refinement brings back onto the answer
/// or onto an alternative kept already ([`confidence::same_pose`]) is dropped.
fn refine_alternatives(
    target: &IcpTarget,
    source: &[[f32; 3]],
    answer: &Candidate,
    poses: &[Matrix4<f64>],
    how: &Refinement,
) -> Vec<Candidate> {
    let source = refine::even_sample(source, refine::REFINE_POINTS);
    let mut kept: Vec<Candidate> = Vec::with_capacity(poses.len());
    for t in poses {
        let c = refine::refine_final(target, &source, answer.start, t, how);
        let t = &c.T_target_source;
        let new = |o: &Candidate| !confidence::same_pose(&o.T_target_source, t);
        if new(answer) && kept.iter().all(new) {
            kept.push(c);
        }
    }
    kept.sort_by(|a, b| b.fitness.total_cmp(&a.fitness));
    kept
}

/// The best of the stage for unsure answers ([`Step::Unsure`]) replaces the answer only when it
/// fits more than this fraction better. The stage turns the source to every orientation, and on
/// shapes with look-alikes (doors, bottles, cones, flower pots) some turn ends on a look-alike that
/// fits a few percent better than the truth; the truth it finds where every other start missed
/// fits far better than the answer. On 3,750 validation pairs, of the stage's bests that would
/// have replaced the answer, those that fit less than 15% better turned 12 right answers wrong
/// (each within 11.5%) and 8 wrong ones right; those that fit more than 15% better turned 8 wrong
/// answers right and none wrong (`BENCHMARK.md`, "The stage for unsure answers: a much better fit
/// or nothing").
const UNSURE_GAIN: f64 = 0.15;

/// Most starts of the adaptive search's last stage that are refined: the best after a short run
/// each ([`refine::shortlist`]; of up to 15 further global hypotheses, and 24 rotations more
/// without the network's turns). Of 34 starts, 12 kept 17 of the 19 any-pose pairs that refining
/// all 34 gained, at about half the stage's time (`BENCHMARK.md`, "A last stage for unsure
/// answers").
const LAST_STAGE_STARTS: usize = 12;

/// Most starts of the last stage that are refined when the answer was nearly sure after the
/// global stage ([`NEARLY_SURE_CONFIDENCE`], or [`AGREED_CONFIDENCE`] with the global stage finding
/// it again): the best of the further global hypotheses after a short run each, of those that
/// fit at least [`NEARLY_SURE_SCREEN_FIT`] as well as the answer's own short run (`BENCHMARK.md`,
/// "Nearly sure after the global stage", "Starts screened against the answer").
const NEARLY_SURE_LAST_STAGE_STARTS: usize = 3;

/// A further global hypothesis of a nearly sure answer's last stage is refined only when its short
/// run ([`refine::shortlist`]) fits at least this share as well as the same run from the answer
/// ([`refine::Screen`]): a blind start must fit clearly better to replace the answer, and one that
/// does not come near it at the coarse distance does not. Measured against refining the best three
/// without a bar: the same recall on 3,750 validation pairs, one answer moved by 0.1 degrees
/// (`BENCHMARK.md`, "Starts screened against the answer").
const NEARLY_SURE_SCREEN_FIT: f64 = 0.95;

/// The global stage refines, of its hypotheses, the one whose short run ([`refine::shortlist`])
/// fits best, and the others whose short run fits at least this share as well as the same run from
/// the answer so far (judged or waiting; [`refine::Screen`]). The best is refined whatever its fit:
/// that the descriptors find the answer again is evidence ([`AGREED_CONFIDENCE`]). At 0.8 and 0.9
/// the search lost pairs (`BENCHMARK.md`, "Starts screened against the answer").
const GLOBAL_SCREEN_FIT: f64 = 0.7;

/// Below this fitness of the answer so far, the global stage describes a pair between sparse and
/// dense at the finer scale too (`global::Density::Mid`): a thinned room's coarse descriptors
/// miss it, and its answers fit under half of the source; objects' answers mostly fit more.
const FINER_BELOW_FITNESS: f64 = 0.5;

/// The answer moved along the motion its surfaces leave `free` (its constraint below
/// [`confidence::UNPINNED_CONSTRAINT`], or barely hold when the answer turned far from the guess:
/// [`HELD_SLID_TURN_DEG`]) to where the caller's guess
/// (`p.t_initial`) puts the source (along it and the other free motions of a plane:
/// [`confidence::FreeScrew::nearest_along_all`]), put back onto the
/// surfaces by ICP from the final distance's stages and moved along the motion again while that
/// fits better; with a warning that says so, when that pose is admitted (`up`), another one, and
/// still fits at least [`HELD_FIT`] as well as the answer (the clouds' edges, not their surfaces,
/// lose some of the fit there). `barely`: the fit barely holds the motion (its constraint above
/// the unpinned line), which the warning says.
fn held_by_guess(
    free: &confidence::FreeScrew,
    barely: bool,
    answer: &Candidate,
    p: &Prepared,
    target: &IcpTarget,
    screen: &[[f32; 3]],
    admits: &dyn Fn(&Matrix4<f64>) -> bool,
) -> Option<(Candidate, String)> {
    let fit = |t: &Matrix4<f64>| target.evaluate(screen, t, p.d_final).0;
    let mut t = free.nearest_along_all(&answer.T_target_source, &p.t_initial, screen);
    let mut best = fit(&t);
    let how = Refinement::new(p.icp, p.d_final, p.d_final, HELD_ITERATIONS);
    for _ in 0..2 {
        let Some(r) = refine::refine_best(target, screen, &[(answer.start, t)], &how) else { break };
        let next = free.nearest_along_all(&r.T_target_source, &p.t_initial, screen);
        let f = fit(&next);
        if f <= best {
            break;
        }
        (t, best) = (next, f);
    }
    let (fitness, inlier_rmse) = target.evaluate(&p.icp_src.points, &t, p.d_final);
    let other = !refine::coincide(&answer.T_target_source, &t, screen, p.d_final);
    // the guess's pose along the motion: nearer the guess than the answer, and not turned away
    // from it (a plane leaves three motions free, one of which reaches the guess only in part)
    let off_guess = |t: &Matrix4<f64>| {
        let at = |m: &Matrix4<f64>, q| nalgebra::Vector3::from(crate::transform::apply(m, q).map(f64::from));
        screen.iter().map(|&q| (at(t, q) - at(&p.t_initial, q)).norm_squared()).sum::<f64>()
    };
    let nearer = off_guess(&t) < off_guess(&answer.T_target_source)
        && crate::transform::rotation_error_deg(&t, &p.t_initial) <= GUESS_TURN_DEG;
    if !(other && nearer && admits(&t) && fitness >= HELD_FIT * answer.fitness) {
        return None;
    }
    let turn = crate::transform::rotation_error_deg(&answer.T_target_source, &t);
    // how far the guess moved the source's centroid, in the caller's units
    let moved = apart(&t, &answer.T_target_source, p.src_n.centroid()) * p.norm.scale;
    let why = if barely {
        format!(
            "the answer follows initialTransform along the motion the fit barely holds (moved {} and turned \
             {turn:.1} degrees from where the fit held it, fitness {fitness:.3} against {:.3}): the clouds tell that \
             motion only weakly, so the guess decides it; a guess off along it is off as much",
            crate::error::num(moved),
            answer.fitness
        )
    } else {
        format!(
            "the answer follows initialTransform along the motion the fit leaves free (moved {} and turned {turn:.1} \
             degrees from where the clouds' edges held it, fitness {fitness:.3} against {:.3}): the clouds cannot tell \
             that motion, the guess does",
            crate::error::num(moved),
            answer.fitness
        )
    };
    Some((Candidate { T_target_source: t, fitness, inlier_rmse, ..*answer }, why))
}

/// How far apart the poses `a` and `b` put the point `at` (the source's centroid; normalised
/// units).
fn apart(a: &Matrix4<f64>, b: &Matrix4<f64>, at: [f64; 3]) -> f64 {
    let c = Point3::from(at);
    (a.transform_point(&c) - b.transform_point(&c)).norm()
}

/// Along a motion the fit barely holds ([`confidence::Evidence::slide`] at or above
/// [`confidence::SLID_FREE`], its constraint above [`confidence::UNPINNED_CONSTRAINT`]), the
/// caller's guess holds the answer ([`held_by_guess`]) only when the answer turned more than this
/// many degrees from it: ICP follows a low relief's gentle slopes from a guess 2 degrees off to
/// the truth, while views of a nearly round teapot turned 25-30 degrees from a guess 1 degree
/// off.
const HELD_SLID_TURN_DEG: f64 = 10.0;

/// Iteration cap of [`held_by_guess`]'s refinements.
const HELD_ITERATIONS: u32 = 30;

/// [`held_by_guess`] keeps the guess's pose along the free motion only when it fits at least this
/// share as well as the answer the clouds' edges held.
const HELD_FIT: f64 = 0.5;

/// How many of the translations the global stage's matches agree on for the answer's rotation
/// are refined ([`Starts::voted_poses`], those that are not the answer's own): the densest, and
/// the next, which on a row of alike parts (two identical pipe spools side by side) is the part
/// the answer is not on, an alternative that fits as well.
const VOTED_MODES: usize = 2;

/// The answer's rotation at the next translation the matches agree on ([`VOTED_MODES`]) is
/// refined only when it already fits at least this share as well as the answer, unrefined.
const NEXT_PART_SCREEN: f64 = 0.5;

/// With `up`, the turns about it (degrees) of the answer that are refined with the translation
/// the global stage's matches agree on for each ([`Starts::voted_pose`]): the look-alikes of a
/// box-like room (see [`search`]).
const UP_TURNS_VOTED: [f64; 3] = [90.0, 180.0, -90.0];

/// Most better poses of the confidence probe that [`settle`] refines in a row.
const MAX_PROBE_STARTS: usize = 4;

/// Judges the candidate `c`; while the confidence probe finds a pose that fits better
/// ([`confidence::Probed::better`]: typically the answer flipped about an axis), refines that
/// pose like a start (`refine`, reported as `c`'s start) and keeps it if it `improves` on `c`
/// (fits better and is another pose), at most [`MAX_PROBE_STARTS`] times. Gives the settled
/// candidate, its evidence and how many probe poses were refined.
fn settle(
    c: Candidate,
    judge: &impl Fn(&Matrix4<f64>) -> Probed,
    mut refine: impl FnMut(Matrix4<f64>) -> Option<Candidate>,
    improves: &impl Fn(&Candidate, &Candidate) -> bool,
) -> (Candidate, Probed, usize) {
    let (mut c, mut probed, mut refined) = (c, judge(&c.T_target_source), 0);
    while let Some(t) = probed.better.filter(|_| refined < MAX_PROBE_STARTS) {
        refined += 1;
        match refine(t) {
            Some(next) if improves(&c, &next) => {
                c = next;
                probed = judge(&c.T_target_source);
            }
            _ => break,
        }
    }
    (c, probed, refined)
}
