//! `arps make-pairs`: writes a pair set generated with the paper's protocol (docs/design.md §8):
//! `NNNNN_source.ply`, `NNNNN_target.ply` (binary PLY), `pairs.tsv` (the format of
//! `fixtures/pairs/pairs.tsv`, GT `T_target_source` row-major) and `pairs.json` (units,
//! protocol parameters, and per pair the shape, seed, overlap and full-shape centroids).

use arps::data::bank;
use arps::data::manifest::{self, Entry, PairMeta, Sidecar};
use arps::data::pairs::{self, check_max_angle, check_pose_angle, check_share};
use arps::data::source::{ShapeSource, Split};
use arps::data::PairParams;
use arps::{io, PointCloud};
use clap::{Args, ValueEnum};
use std::path::PathBuf;

#[derive(Clone, Copy, ValueEnum)]
pub enum SplitArg {
    /// Held-out validation shapes (default; use these for evaluation).
    Val,
    /// Training shapes.
    Train,
}

#[derive(Args)]
pub struct MakePairsArgs {
    /// Output directory (created if missing).
    #[arg(long)]
    out: PathBuf,
    /// Number of pairs.
    #[arg(long, default_value_t = 100)]
    count: u64,
    /// Seed of the set: pair i is pair (seed * 2^32 + i) of the split.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// A directory of meshes (OBJ/OFF/PLY/STL, searched recursively) to draw shapes from too.
    #[arg(long)]
    bank: Option<PathBuf>,
    /// Which shapes.
    #[arg(long, value_enum, default_value_t = SplitArg::Val)]
    split: SplitArg,
    /// Procedural shapes only (ignore --bank).
    #[arg(long)]
    procedural_only: bool,
    /// Fraction of the bank held out for validation (by a hash of each mesh's relative path).
    #[arg(long, default_value_t = 0.15)]
    val_fraction: f64,
    /// Probability that a pair uses a bank shape (when the split has any).
    #[arg(long, default_value_t = 0.3)]
    bank_fraction: f64,
    /// Range of the relative rotation (source to target), degrees: each Euler angle in [-a, a].
    /// 45 is the paper's protocol; 180 gives any-pose pairs (any relative rotation).
    #[arg(long, visible_alias = "rotation-range", default_value_t = 45.0)]
    max_angle: f64,
    /// Upright pairs: the relative rotation's Euler angles about x and y in [-t, t] degrees,
    /// the one about z still in [-a, a] (`--max-angle`): the clouds share the up axis z within
    /// about this tilt, as gravity-aligned scans do (`--max-angle 180 --max-tilt 0`: any turn
    /// about z, for the `up` option)
    #[arg(long)]
    max_tilt: Option<f64>,
    /// Maximum translation, normalised units.
    #[arg(long, default_value_t = 0.5)]
    max_translation: f64,
    /// Noise sigma, normalised units (clipped at 0.05, as the protocol).
    #[arg(long, default_value_t = 0.01)]
    noise: f64,
    /// Points per cloud.
    #[arg(long, default_value_t = 1024)]
    points: usize,
    /// Points drawn from each shape's surface before cropping (default: the protocol's 4,096, or 4x
    /// `--points` when that is more, so that no cloud repeats a sample). Both clouds are
    /// resampled from them, so at 4x the points about a third of the overlap's points are the same
    /// surface sample in both (under independent noise); real scans share none. 64x makes such
    /// twins rare (65,536 for 1,024 points: about 2% of the overlap's points).
    #[arg(long)]
    dense_points: Option<usize>,
    /// Turn each whole shape by Euler angles up to this many degrees before cropping (0, the
    /// paper's protocol, keeps the shape's own, usually upright, orientation; 180: any pose).
    #[arg(long, default_value_t = 0.0)]
    pose_angle: f64,
    /// Fraction of the shape's dense sample each crop keeps (the protocol's 0.7); with
    /// `--target-keep`, the source's crop only.
    #[arg(long, default_value_t = 0.7)]
    keep: f64,
    /// Fraction the target's crop keeps instead (1: the whole shape, as when a scan is
    /// registered onto a model); default `--keep`.
    #[arg(long)]
    target_keep: Option<f64>,
    /// Points in each target cloud instead of `--points` (a model sampled more densely than
    /// a scan of it); default `--points`.
    #[arg(long)]
    target_points: Option<usize>,
    /// Stray returns added to each source, as a share of its points: scattered uniformly over a
    /// cube three times the shape's size (not in the paper's protocol; default 0). The surface
    /// points stay the pair's.
    #[arg(long, default_value_t = 0.0)]
    stray: f64,
    /// The same for each target (default 0: a clean target, as a model is).
    #[arg(long, default_value_t = 0.0)]
    target_stray: f64,
    /// A support plane added to each source, as a share of its points: a level square (z up in
    /// the shape's frame) at the object's lowest point, reaching beyond the source by its largest
    /// half-extent on each side, as the table under a scanned object (not in the paper's
    /// protocol; default 0). The surface points stay the pair's.
    #[arg(long, default_value_t = 0.0)]
    support: f64,
    /// The same plane in each target, as a share of its points (the same table in both scans;
    /// default 0: a target without it, as a model is).
    #[arg(long, default_value_t = 0.0)]
    target_support: f64,
    /// With `--target-support`: the object was moved on the table between the two scans, so the
    /// target's plane is level under the target's own points instead of the source's plane moved
    /// by the ground truth (give `--max-tilt 0` for turns about the table's normal only).
    #[arg(long)]
    support_moved: bool,
}

/// A crop's fraction given by a user: in (0, 1].
fn check_keep(flag: &str, r: f64) -> Result<f64, String> {
    if r.is_finite() && r > 0.0 && r <= 1.0 {
        Ok(r)
    } else {
        Err(format!("{flag} {r}: expected a fraction in (0, 1]"))
    }
}

/// The dense sample for clouds of `points` points: the protocol's 4,096 (for its 1,024 points),
/// or 4x the points when that is more. A crop keeps about 0.7 of it, and a cloud larger than
/// its crop would repeat samples (each repeat a noisy copy of the same surface point).
fn default_dense_points(points: usize) -> usize {
    PairParams::default().dense_points.max(points.saturating_mul(4))
}

/// Most `--dense-points`: a shape's dense sample is held in memory whole.
const MAX_DENSE_POINTS: usize = 1 << 22;

/// The distance written as `overlap_threshold`: five noise sigmas at the default noise.
const OVERLAP_THRESHOLD: f64 = 0.05;

pub fn run(a: MakePairsArgs) -> Result<(), String> {
    let pose_angle_deg = check_pose_angle(a.pose_angle).map_err(|e| format!("--pose-angle {e}"))?;
    let max_angle_deg = check_max_angle(a.max_angle).map_err(|e| format!("--max-angle {e}"))?;
    let max_tilt_deg = a.max_tilt.map(check_max_angle).transpose().map_err(|e| format!("--max-tilt {e}"))?;
    let keep_ratio = check_keep("--keep", a.keep)?;
    let target_keep_ratio = a.target_keep.map(|r| check_keep("--target-keep", r)).transpose()?;
    let stray = check_share(a.stray).map_err(|e| format!("--stray {e}"))?;
    let target_stray = check_share(a.target_stray).map_err(|e| format!("--target-stray {e}"))?;
    let support = check_share(a.support).map_err(|e| format!("--support {e}"))?;
    let target_support = check_share(a.target_support).map_err(|e| format!("--target-support {e}"))?;
    if a.points == 0 || a.target_points == Some(0) {
        return Err("--points and --target-points: a cloud needs at least one point".into());
    }
    let dense_points =
        a.dense_points.unwrap_or_else(|| default_dense_points(a.points.max(a.target_points.unwrap_or(0))));
    if !(16..=MAX_DENSE_POINTS).contains(&dense_points) {
        return Err(match a.dense_points {
            Some(n) => format!("--dense-points {n}: expected 16 to {MAX_DENSE_POINTS}"),
            None => format!(
                "--points {}: the dense sample would be 4x that, above the most ({MAX_DENSE_POINTS}); give --dense-points (a cloud larger than 0.7x it repeats samples)",
                a.points
            ),
        });
    }
    let mut source = match (&a.bank, a.procedural_only) {
        (Some(dir), false) => {
            let b = bank::load_dir(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
            for s in &b.skipped {
                eprintln!("arps: bank: skipped {}: {}", s.name, s.reason);
            }
            eprintln!("arps: bank: {} meshes usable, {} skipped", b.meshes.len(), b.skipped.len());
            ShapeSource::with_bank(b, a.val_fraction)
        }
        _ => ShapeSource::procedural(),
    };
    source.bank_fraction = a.bank_fraction;
    let split = match a.split {
        SplitArg::Val => Split::Val,
        SplitArg::Train => Split::Train,
    };
    let params = PairParams {
        max_angle_deg,
        max_tilt_deg,
        max_translation: a.max_translation,
        noise_sigma: a.noise,
        points: a.points,
        dense_points,
        pose_angle_deg,
        keep_ratio,
        target_keep_ratio,
        target_points: a.target_points,
        ..PairParams::default()
    };
    std::fs::create_dir_all(&a.out).map_err(|e| format!("{}: {e}", a.out.display()))?;
    let mut entries = Vec::new();
    let mut metas = Vec::new();
    for i in 0..a.count {
        let index = (a.seed << 32).wrapping_add(i);
        let mut pair = source.pair(split, index, &params).map_err(|e| format!("pair {i}: {e}"))?;
        if stray > 0.0 || target_stray > 0.0 {
            pairs::add_strays(&mut pair, stray, target_stray);
        }
        if support > 0.0 || target_support > 0.0 {
            pairs::add_support(
                &mut pair,
                support,
                target_support,
                a.support_moved,
                params.noise_sigma,
                params.noise_clip,
            );
        }
        let stem = format!("{i:05}");
        let (sf, tf) = (format!("{stem}_source.ply"), format!("{stem}_target.ply"));
        for (f, pts) in [(&sf, &pair.source), (&tf, &pair.target)] {
            let path = a.out.join(f);
            std::fs::write(&path, io::write_ply_binary(&PointCloud::new(pts.clone())))
                .map_err(|e| format!("{}: {e}", path.display()))?;
        }
        let short = pair.shape.strip_prefix("procedural/").unwrap_or(&pair.shape);
        let name = format!("{stem}-{}", short.replace('/', "-"));
        entries.push(Entry {
            name: name.clone(),
            source: sf,
            target: tf,
            overlap_threshold: OVERLAP_THRESHOLD,
            note: format!(
                "synthetic: {} ({:?} split), pair seed {}, crop overlap {:.3}, normalised shape units",
                pair.shape, split, pair.seed, pair.overlap
            ),
            T_target_source: pair.T_target_source,
        });
        metas.push(PairMeta {
            name,
            shape: pair.shape.clone(),
            seed: pair.seed,
            overlap: pair.overlap,
            centroid_source: pair.centroid_source,
            centroid_target: pair.centroid_target,
        });
    }
    let tsv = a.out.join("pairs.tsv");
    std::fs::write(&tsv, manifest::format(&entries)).map_err(|e| format!("{}: {e}", tsv.display()))?;
    let mut generator = serde_json::json!({
            "command": "arps make-pairs",
            "version": env!("CARGO_PKG_VERSION"),
            "split": format!("{split:?}").to_lowercase(),
            "seed": a.seed,
            "count": a.count,
            "bank": a.bank.as_ref().filter(|_| !a.procedural_only).map(|p| p.display().to_string()),
            "bank_fraction": a.bank_fraction,
            "val_fraction": a.val_fraction,
    });
    // strays and support planes are not in PairParams (they are added to a made pair): recorded
    // here when present
    if stray > 0.0 || target_stray > 0.0 {
        generator["stray"] = stray.into();
        generator["target_stray"] = target_stray.into();
    }
    if support > 0.0 || target_support > 0.0 {
        generator["support"] = support.into();
        generator["target_support"] = target_support.into();
        generator["support_moved"] = a.support_moved.into();
    }
    let sidecar = Sidecar { units: "normalized".into(), generator, params, pairs: metas };
    let json = a.out.join("pairs.json");
    std::fs::write(&json, serde_json::to_string_pretty(&sidecar).map_err(|e| e.to_string())? + "\n")
        .map_err(|e| format!("{}: {e}", json.display()))?;
    out!("wrote {} pairs to {}", a.count, a.out.display());
    Ok(())
}
