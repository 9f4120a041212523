//! The paper's metrics (docs/design.md §9): geodesic rotation error in degrees, translation error,
//! MRE/MTE over all pairs, recall (RE < θ_R **and** TE < θ_t, strict), RRE/RTE over the recalled
//! pairs, and recall-vs-threshold curves drawn as a plain SVG.

use crate::transform::{rotation_error_deg, translation_error};
use nalgebra::Matrix4;
use serde::Serialize;

/// Errors of one estimate.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PairError {
    /// Geodesic rotation error, degrees.
    pub rot_deg: f64,
    /// Translation error, in whatever units the caller scaled to.
    pub trans: f64,
}

/// RE and TE of `pred` against `gt`, TE divided by `scale` (1 for unit-scale data).
pub fn pair_error(pred: &Matrix4<f64>, gt: &Matrix4<f64>, scale: f64) -> PairError {
    let ok = pred.iter().all(|v| v.is_finite());
    if !ok {
        return PairError { rot_deg: 180.0, trans: f64::INFINITY };
    }
    PairError { rot_deg: rotation_error_deg(pred, gt), trans: translation_error(pred, gt) / scale }
}

/// The paper's table figures for one method.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Summary {
    /// Pairs.
    pub pairs: usize,
    /// Mean rotation error over all pairs, degrees.
    pub mre: f64,
    /// Mean translation error over all pairs.
    pub mte: f64,
    /// Fraction of pairs with RE < θ_R and TE < θ_t.
    pub recall: f64,
    /// Mean RE over recalled pairs (NaN when none).
    pub rre: f64,
    /// Mean TE over recalled pairs (NaN when none).
    pub rte: f64,
    /// Mean wall-clock milliseconds per pair.
    pub ms_per_pair: f64,
}

/// True when a pair is recalled (strict inequalities, as DGR).
pub fn recalled(e: &PairError, rot_thr: f64, trans_thr: f64) -> bool {
    e.rot_deg < rot_thr && e.trans < trans_thr
}

/// A miss that fits the data as well as the truth does: the estimate failed the recall
/// thresholds (`recalled` false), but its fitness is at least `gt_fitness` (the truth refined by
/// the same ICP) minus `margin`. No choice by fitness can tell such a pose from the truth (a cone
/// turned about its axis, a box flipped): `arps eval`'s `fit>=GT` column.
pub fn ambiguous_miss(recalled: bool, fitness: Option<f64>, gt_fitness: f64, margin: f64) -> bool {
    !recalled && fitness.is_some_and(|f| f >= gt_fitness - margin)
}

/// Summarises errors and times (ms) at the thresholds.
pub fn summarize(errors: &[PairError], times_ms: &[f64], rot_thr: f64, trans_thr: f64) -> Summary {
    let n = errors.len();
    if n == 0 {
        return Summary::default();
    }
    let mean = |v: &mut dyn Iterator<Item = f64>| {
        let (s, c) = v.fold((0.0, 0usize), |(s, c), x| (s + x, c + 1));
        if c == 0 {
            f64::NAN
        } else {
            s / c as f64
        }
    };
    let rec: Vec<&PairError> = errors.iter().filter(|e| recalled(e, rot_thr, trans_thr)).collect();
    Summary {
        pairs: n,
        mre: mean(&mut errors.iter().map(|e| e.rot_deg)),
        mte: mean(&mut errors.iter().map(|e| e.trans)),
        recall: rec.len() as f64 / n as f64,
        rre: mean(&mut rec.iter().map(|e| e.rot_deg)),
        rte: mean(&mut rec.iter().map(|e| e.trans)),
        ms_per_pair: mean(&mut times_ms.iter().copied()),
    }
}

/// Recall as the rotation threshold sweeps `thresholds` (translation held at `trans_thr`).
pub fn recall_vs_rotation(errors: &[PairError], thresholds: &[f64], trans_thr: f64) -> Vec<f64> {
    let n = errors.len().max(1) as f64;
    thresholds.iter().map(|&t| errors.iter().filter(|e| recalled(e, t, trans_thr)).count() as f64 / n).collect()
}

/// Recall as the translation threshold sweeps `thresholds` (rotation held at `rot_thr`).
pub fn recall_vs_translation(errors: &[PairError], thresholds: &[f64], rot_thr: f64) -> Vec<f64> {
    let n = errors.len().max(1) as f64;
    thresholds.iter().map(|&t| errors.iter().filter(|e| recalled(e, rot_thr, t)).count() as f64 / n).collect()
}

/// `n + 1` evenly spaced values from 0 to `max`.
pub fn linspace(max: f64, n: usize) -> Vec<f64> {
    (0..=n).map(|i| max * i as f64 / n as f64).collect()
}

const COLORS: [&str; 8] = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"];

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// Two panels side by side: recall vs rotation threshold (0..`rot_max` degrees, translation held
/// at `trans_thr`) and recall vs translation threshold (0..`trans_max`, rotation held at
/// `rot_thr`), one polyline per method, with axes, ticks and a legend. A self-contained SVG.
pub fn recall_svg(
    methods: &[(String, Vec<PairError>)],
    rot_thr: f64,
    trans_thr: f64,
    rot_max: f64,
    trans_max: f64,
    title: &str,
) -> String {
    let (pw, ph) = (360.0, 260.0);
    let (ml, mt, mb, gap) = (55.0, 40.0, 45.0, 70.0);
    let legend_h = 18.0 * methods.len() as f64 + 10.0;
    let width = ml + pw + gap + pw + 20.0;
    let height = mt + ph + mb + legend_h;
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{height}\" viewBox=\"0 0 {width} {height}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n<text x=\"{}\" y=\"20\" text-anchor=\"middle\" font-size=\"14\">{}</text>\n",
        width / 2.0,
        escape(title)
    );
    let steps = 120;
    let panels = [
        (ml, rot_max, format!("rotation threshold (deg), TE < {trans_thr}"), true),
        (ml + pw + gap, trans_max, format!("translation threshold, RE < {rot_thr} deg"), false),
    ];
    for (x0, max, label, is_rot) in panels {
        let y0 = mt;
        s.push_str(&format!(
            "<rect x=\"{x0}\" y=\"{y0}\" width=\"{pw}\" height=\"{ph}\" fill=\"none\" stroke=\"black\"/>\n"
        ));
        for i in 0..=5 {
            let f = i as f64 / 5.0;
            let x = x0 + f * pw;
            let y = y0 + ph - f * ph;
            s.push_str(&format!(
                "<line x1=\"{x0}\" y1=\"{y}\" x2=\"{}\" y2=\"{y}\" stroke=\"#ddd\"/>\n<text x=\"{}\" y=\"{}\" text-anchor=\"end\">{:.1}</text>\n",
                x0 + pw,
                x0 - 5.0,
                y + 4.0,
                f
            ));
            s.push_str(&format!(
                "<line x1=\"{x}\" y1=\"{y0}\" x2=\"{x}\" y2=\"{}\" stroke=\"#ddd\"/>\n<text x=\"{x}\" y=\"{}\" text-anchor=\"middle\">{}</text>\n",
                y0 + ph,
                y0 + ph + 15.0,
                if is_rot { format!("{:.0}", f * max) } else { format!("{:.2}", f * max) }
            ));
        }
        s.push_str(&format!(
            "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>\n<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" transform=\"rotate(-90 {} {})\">recall</text>\n",
            x0 + pw / 2.0,
            y0 + ph + 32.0,
            escape(&label),
            x0 - 38.0,
            y0 + ph / 2.0,
            x0 - 38.0,
            y0 + ph / 2.0
        ));
        let th = linspace(max, steps);
        for (k, (_, errs)) in methods.iter().enumerate() {
            let r = if is_rot {
                recall_vs_rotation(errs, &th, trans_thr)
            } else {
                recall_vs_translation(errs, &th, rot_thr)
            };
            let pts: Vec<String> =
                th.iter().zip(&r).map(|(t, v)| format!("{:.1},{:.1}", x0 + t / max * pw, y0 + ph - v * ph)).collect();
            s.push_str(&format!(
                "<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"2\" points=\"{}\"/>\n",
                COLORS[k % COLORS.len()],
                pts.join(" ")
            ));
        }
    }
    for (k, (name, _)) in methods.iter().enumerate() {
        let y = mt + ph + mb + 14.0 + 18.0 * k as f64;
        s.push_str(&format!(
            "<line x1=\"{ml}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"{}\" stroke-width=\"3\"/><text x=\"{}\" y=\"{y}\">{}</text>\n",
            y - 4.0,
            ml + 25.0,
            y - 4.0,
            COLORS[k % COLORS.len()],
            ml + 32.0,
            escape(name)
        ));
    }
    s.push_str("</svg>\n");
    s
}

/// Exact two-sided McNemar test for two methods scored on the same pairs: `only_a` pairs
/// recalled by the first method alone, `only_b` by the second alone (the discordant pairs; pairs
/// both or neither recall carry no information). Under "the methods are equally good" each
/// discordant pair is a fair coin, so the p-value is the two-sided binomial tail
/// `min(1, 2 P[X ≤ min(only_a, only_b)])`, `X ~ Binomial(only_a + only_b, 1/2)`. 1 when there are
/// no discordant pairs.
pub fn mcnemar_p(only_a: usize, only_b: usize) -> f64 {
    let n = only_a + only_b;
    let k = only_a.min(only_b);
    if n == 0 {
        return 1.0;
    }
    // ln C(n, i) by the running product, each term scaled by 2^-n in the log domain
    let ln_half_n = -(n as f64) * std::f64::consts::LN_2;
    let mut ln_c = 0.0;
    let mut tail = 0.0;
    for i in 0..=k {
        if i > 0 {
            ln_c += ((n - i + 1) as f64).ln() - (i as f64).ln();
        }
        tail += (ln_c + ln_half_n).exp();
    }
    (2.0 * tail).min(1.0)
}
