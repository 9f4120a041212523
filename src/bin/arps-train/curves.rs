//! `arps-train curves`: validation recall and MRE (network only, and network + ICP where
//! measured) and the training loss against wall-clock minutes, one colour per run, as a plain SVG.

use arps::train::run::log;
use std::path::{Path, PathBuf};

const COLORS: [&str; 6] = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b"];

/// (label, colour, points, dashed)
type Series = (String, String, Vec<(f64, f64)>, bool);

struct Panel {
    title: &'static str,
    series: Vec<Series>,
}

fn panel_svg(p: &Panel, x0: f64, y0: f64, w: f64, h: f64, xmax: f64, xlabel: &str) -> String {
    let ys: Vec<f64> = p.series.iter().flat_map(|s| s.2.iter().map(|q| q.1)).filter(|v| v.is_finite()).collect();
    let (mut lo, mut hi) = ys.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    if !lo.is_finite() {
        (lo, hi) = (0.0, 1.0);
    }
    if hi - lo < 1e-9 {
        hi = lo + 1.0;
    }
    let lo = if lo > 0.0 && lo < 0.5 * hi { 0.0 } else { lo };
    let sx = |x: f64| x0 + w * x / xmax.max(1e-9);
    let sy = |y: f64| y0 + h - h * (y - lo) / (hi - lo);
    let mut s = format!(
        "<rect x=\"{x0}\" y=\"{y0}\" width=\"{w}\" height=\"{h}\" fill=\"none\" stroke=\"#999\"/>\n<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>\n",
        x0 + w / 2.0,
        y0 - 8.0,
        p.title
    );
    for i in 0..=4 {
        let v = lo + (hi - lo) * i as f64 / 4.0;
        s += &format!(
            "<text x=\"{}\" y=\"{}\" text-anchor=\"end\" font-size=\"10\">{:.3}</text>\n",
            x0 - 4.0,
            sy(v) + 3.0,
            v
        );
        let xv = xmax * i as f64 / 4.0;
        s += &format!(
            "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" font-size=\"10\">{:.0}</text>\n",
            sx(xv),
            y0 + h + 14.0,
            xv
        );
    }
    s += &format!(
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" font-size=\"10\">{}</text>\n",
        x0 + w / 2.0,
        y0 + h + 28.0,
        xlabel
    );
    for (_, color, pts, dashed) in &p.series {
        let path: Vec<String> =
            pts.iter().filter(|q| q.1.is_finite()).map(|q| format!("{:.1},{:.1}", sx(q.0), sy(q.1))).collect();
        if !path.is_empty() {
            s += &format!(
                "<polyline fill=\"none\" stroke=\"{color}\" stroke-width=\"1.5\"{} points=\"{}\"/>\n",
                if *dashed { " stroke-dasharray=\"4,3\"" } else { "" },
                path.join(" ")
            );
        }
    }
    s
}

pub fn run(runs: &[PathBuf], out: &Path, cpu: bool) -> Result<(), String> {
    let mut panels = [
        Panel { title: "validation recall (solid: network, dashed: +ICP)", series: vec![] },
        Panel { title: "validation MRE, degrees (network)", series: vec![] },
        Panel { title: "training loss (total)", series: vec![] },
    ];
    let mut xmax: f64 = 1.0;
    let mut legend = Vec::new();
    for (k, run) in runs.iter().enumerate() {
        let lines = log::read(&run.join("log.jsonl")).map_err(|e| format!("{}: {e}", run.display()))?;
        let color = COLORS[k % COLORS.len()].to_string();
        let name = run.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let (mut rec, mut icp, mut mre, mut loss) = (vec![], vec![], vec![], vec![]);
        for l in &lines {
            let t = l[if cpu { "cpu" } else { "elapsed" }].as_f64().unwrap_or(0.0) / 60.0;
            xmax = xmax.max(t);
            match l["kind"].as_str() {
                Some("val") => {
                    rec.push((t, l["val"]["net_recall"].as_f64().unwrap_or(f64::NAN)));
                    mre.push((t, l["val"]["net_mre"].as_f64().unwrap_or(f64::NAN)));
                    if let Some(v) = l["val"]["icp_recall"].as_f64() {
                        icp.push((t, v));
                    }
                }
                Some("step") => loss.push((t, l["loss"]["total"].as_f64().unwrap_or(f64::NAN))),
                _ => {}
            }
        }
        panels[0].series.push((name.clone(), color.clone(), rec, false));
        panels[0].series.push((name.clone(), color.clone(), icp, true));
        panels[1].series.push((name.clone(), color.clone(), mre, false));
        panels[2].series.push((name.clone(), color.clone(), loss, false));
        legend.push((name, color));
    }
    let (pw, ph, ml, mt, gap) = (300.0, 220.0, 60.0, 40.0, 80.0);
    let width = ml + 3.0 * (pw + gap);
    let height = mt + ph + 60.0 + 18.0 * legend.len() as f64;
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{height}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    );
    for (i, p) in panels.iter().enumerate() {
        let xl = if cpu { "process CPU minutes" } else { "wall-clock minutes" };
        s += &panel_svg(p, ml + i as f64 * (pw + gap), mt, pw, ph, xmax, xl);
    }
    for (i, (name, color)) in legend.iter().enumerate() {
        let y = mt + ph + 50.0 + 18.0 * i as f64;
        s += &format!("<line x1=\"{ml}\" y1=\"{y}\" x2=\"{}\" y2=\"{y}\" stroke=\"{color}\" stroke-width=\"2\"/><text x=\"{}\" y=\"{}\">{name}</text>\n", ml + 20.0, ml + 26.0, y + 4.0);
    }
    s += "</svg>\n";
    std::fs::write(out, s).map_err(|e| format!("{}: {e}", out.display()))
}
