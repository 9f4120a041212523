//! `arps compare A.json B.json`: two `arps eval --json` results on the same pairs, pair by pair.
//!
//! Recall alone cannot say whether two models differ: on 500 pairs a recall of 0.95 has a standard
//! error of about 0.01, and most pairs are registered by both or by neither. The informative pairs
//! are the discordant ones, registered by one side only; under "equally good" each is a coin toss,
//! which the exact McNemar test turns into a p-value. A miss whose fitness is within the eval's
//! ambiguity margin of the truth's (`fit>=GT`) is a geometric ambiguity that no fitness-based
//! choice can resolve, so the discordant misses are also counted without those.
//!
//! `--by-category` adds recall per shape category (the pair names of `arps make-pairs`:
//! `<index>-<category>-<shape id>`, `bank` for the shape bank's meshes).

use arps::data::metrics::{ambiguous_miss, mcnemar_p, recalled, PairError};
use clap::{Args, ValueEnum};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct CompareArgs {
    /// The first `arps eval --json` result (A).
    a: PathBuf,
    /// The second (B), on the same pairs.
    b: PathBuf,
    /// Also print recall per shape category (for `--methods`, or else for `network` and
    /// `network + multi-start ICP`).
    #[arg(long)]
    by_category: bool,
    /// Methods to compare, comma-separated, by `arps eval --methods` key (`network`, `network-icp`,
    /// `multi-start`, ...) or by row name (default: every method both files have).
    #[arg(long, value_delimiter = ',')]
    methods: Option<Vec<String>>,
}

/// One method's outcome on one pair.
#[derive(Clone, Copy)]
struct Outcome {
    recalled: bool,
    /// Missed, with a fitness within the ambiguity margin of the truth's.
    ambiguous: bool,
}

/// One eval result: pair names, and per method the outcome of each pair, in pair order.
struct EvalResult {
    weights: String,
    /// The multi-start method's starts (eval writes them since session 7).
    starts: Option<String>,
    /// The seed of `eval --perturb` (null when the sources were not moved).
    perturb: Value,
    /// Its largest Euler angle, degrees (`eval --perturb-angle`; results written before it had
    /// the option moved the sources by at most 45); `None` when the sources were not moved.
    perturb_angle: Option<f64>,
    rot_threshold: f64,
    trans_threshold: f64,
    names: Vec<String>,
    methods: Vec<String>,
    outcomes: BTreeMap<String, Vec<Outcome>>,
}

fn read(path: &Path) -> Result<EvalResult, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let bad = |what: &str| format!("{}: not an `arps eval --json` result ({what})", path.display());
    let v: Value = serde_json::from_str(text.trim()).map_err(|e| format!("{}: {e}", path.display()))?;
    let num = |key: &str| v[key].as_f64().ok_or_else(|| bad(&format!("no `{key}`")));
    let rot_threshold = num("rot_threshold_deg")?;
    let trans_threshold = num("trans_threshold")?;
    let margin = num("ambiguity_margin")?;
    let methods: Vec<String> = v["methods"]
        .as_array()
        .ok_or_else(|| bad("no `methods`"))?
        .iter()
        .map(|m| m["name"].as_str().map(str::to_string).ok_or_else(|| bad("a method without a name")))
        .collect::<Result<_, _>>()?;
    let pairs = v["per_pair"].as_array().ok_or_else(|| bad("no `per_pair`"))?;
    if pairs.is_empty() {
        return Err(bad("no pairs"));
    }
    let mut names = Vec::with_capacity(pairs.len());
    let mut outcomes: BTreeMap<String, Vec<Outcome>> = BTreeMap::new();
    for p in pairs {
        names.push(p["name"].as_str().ok_or_else(|| bad("a pair without a name"))?.to_string());
        let gt_fitness = p["gt_fitness"].as_f64().ok_or_else(|| bad("a pair without `gt_fitness`"))?;
        for r in p["results"].as_array().ok_or_else(|| bad("a pair without `results`"))? {
            let method = r["method"].as_str().ok_or_else(|| bad("a result without `method`"))?;
            // a failed call counts as a miss (eval scores it as the identity)
            let e = PairError {
                rot_deg: r["rot_deg"].as_f64().unwrap_or(f64::INFINITY),
                trans: r["trans"].as_f64().unwrap_or(f64::INFINITY),
            };
            let hit = r["error"].is_null() && recalled(&e, rot_threshold, trans_threshold);
            let ambiguous = ambiguous_miss(hit, r["fitness"].as_f64(), gt_fitness, margin);
            outcomes.entry(method.to_string()).or_default().push(Outcome { recalled: hit, ambiguous });
        }
    }
    if outcomes.values().any(|o| o.len() != names.len()) {
        return Err(bad("a method is missing on some pairs"));
    }
    Ok(EvalResult {
        weights: v["weights"].as_str().unwrap_or("?").to_string(),
        starts: v["starts"].as_array().map(|a| a.iter().filter_map(Value::as_str).collect::<Vec<_>>().join(", ")),
        perturb: v["perturb"].clone(),
        perturb_angle: v["perturb_angle_deg"].as_f64().or((!v["perturb"].is_null()).then_some(45.0)),
        rot_threshold,
        trans_threshold,
        names,
        methods,
        outcomes,
    })
}

/// `<index>-<category>-<id>` → category; anything else → the whole name.
fn category(name: &str) -> &str {
    let mut parts = name.splitn(3, '-');
    match (parts.next(), parts.next(), parts.next()) {
        (Some(_), Some(c), Some(_)) => c,
        _ => name,
    }
}

pub fn run(args: CompareArgs) -> Result<(), String> {
    let a = read(&args.a)?;
    let b = read(&args.b)?;
    if a.names != b.names {
        return Err(format!(
            "{} and {} are not on the same pairs ({} and {} pairs{})",
            args.a.display(),
            args.b.display(),
            a.names.len(),
            b.names.len(),
            if a.names.len() == b.names.len() { ", different names or order" } else { "" }
        ));
    }
    if a.perturb != b.perturb || a.perturb_angle != b.perturb_angle {
        let angle = |r: &EvalResult| r.perturb_angle.map(|d| format!(" --perturb-angle {d}")).unwrap_or_default();
        return Err(format!(
            "{} and {} moved the sources differently (--perturb {}{} and {}{})",
            args.a.display(),
            args.b.display(),
            a.perturb,
            angle(&a),
            b.perturb,
            angle(&b)
        ));
    }
    if a.rot_threshold != b.rot_threshold || a.trans_threshold != b.trans_threshold {
        return Err(format!(
            "different recall thresholds: {} deg / {} against {} deg / {}",
            a.rot_threshold, a.trans_threshold, b.rot_threshold, b.trans_threshold
        ));
    }
    let common: Vec<&String> = a.methods.iter().filter(|m| b.outcomes.contains_key(*m)).collect();
    // eval's keys (`multi-start`) name the rows (`network + multi-start ICP`)
    let requested: Option<Vec<String>> = args.methods.as_ref().map(|list| {
        list.iter()
            .map(|m| match super::eval::Method::from_str(m, false) {
                Ok(method) => method.name().to_string(),
                Err(_) => m.clone(),
            })
            .collect()
    });
    let methods: Vec<&String> = match &requested {
        Some(list) => {
            for m in list {
                if !common.contains(&m) {
                    return Err(format!("no method `{m}` in both files (they have: {})", join(&common)));
                }
            }
            common.into_iter().filter(|c| list.contains(c)).collect()
        }
        None => common,
    };
    let n = a.names.len();
    out!("arps compare: {n} pairs");
    let describe = |r: &EvalResult| match &r.starts {
        Some(s) => format!("{}; multi-start: {s}", r.weights),
        None => r.weights.clone(),
    };
    out!("  A: {} ({})", args.a.display(), describe(&a));
    out!("  B: {} ({})", args.b.display(), describe(&b));
    out!(
        "  recall: RE < {} deg and TE < {}; A only / B only: pairs one side registers and the other misses \
         (in brackets: of those misses, the unambiguous ones, fit < GT); p: exact two-sided McNemar",
        a.rot_threshold,
        a.trans_threshold
    );
    out!("{:<28} {:>8} {:>8} {:>13} {:>13} {:>9}", "method", "recall A", "recall B", "A only", "B only", "p");
    for m in &methods {
        let (oa, ob) = (&a.outcomes[*m], &b.outcomes[*m]);
        let recall = |o: &[Outcome]| o.iter().filter(|x| x.recalled).count() as f64 / n as f64;
        // A only: A recalls, B misses (unambiguous: B's miss fits worse than the truth)
        let only = |x: &[Outcome], y: &[Outcome]| {
            let idx: Vec<usize> = (0..n).filter(|&i| x[i].recalled && !y[i].recalled).collect();
            let clear = idx.iter().filter(|&&i| !y[i].ambiguous).count();
            (idx.len(), clear)
        };
        let (a_only, a_clear) = only(oa, ob);
        let (b_only, b_clear) = only(ob, oa);
        out!(
            "{:<28} {:>8.4} {:>8.4} {:>13} {:>13} {:>9.2e}",
            m,
            recall(oa),
            recall(ob),
            format!("{a_only} ({a_clear})"),
            format!("{b_only} ({b_clear})"),
            mcnemar_p(a_only, b_only)
        );
    }
    if args.by_category {
        let shown: Vec<&String> = match &requested {
            Some(_) => methods.clone(),
            None => methods.iter().copied().filter(|m| *m == "network" || *m == "network + multi-start ICP").collect(),
        };
        let mut cats: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
        for (i, name) in a.names.iter().enumerate() {
            cats.entry(category(name)).or_default().push(i);
        }
        out!("");
        let header: String = shown.iter().map(|m| format!(" {:>28}", format!("{m} A / B"))).collect();
        out!("{:<14} {:>5}{header}", "category", "pairs");
        for (cat, idx) in &cats {
            let cells: String = shown
                .iter()
                .map(|m| {
                    let r = |o: &[Outcome]| idx.iter().filter(|&&i| o[i].recalled).count() as f64 / idx.len() as f64;
                    format!(" {:>28}", format!("{:.3} / {:.3}", r(&a.outcomes[*m]), r(&b.outcomes[*m])))
                })
                .collect();
            out!("{cat:<14} {:>5}{cells}", idx.len());
        }
    }
    Ok(())
}

fn join(v: &[&String]) -> String {
    v.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(", ")
}
