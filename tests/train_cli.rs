#![cfg(feature = "train")]
//! `arps-train` end to end on the tiny preset (seconds): a short run lowers the loss and writes a
//! checkpoint and a log; `--resume` continues exactly (same parameters and Adam moments as an
//! uninterrupted run of the same total steps); `export` writes weights the engine loads and
//! `arps info` describes.

mod common;
use arps::train::run::{checkpoint, log};
use std::path::Path;
use std::process::Command;

/// A run directory for the trainer to create: a path inside a fresh scratch directory, removed
/// with it.
fn dir(name: &str) -> common::scratch::Scratch {
    common::scratch(&format!("train-test-{name}"))
}

fn train(run: &Path, extra: &[&str]) {
    let mut args: Vec<String> = ["train", "--run"].iter().map(|s| s.to_string()).collect();
    args.push(run.to_string_lossy().into_owned());
    args.extend(extra.iter().map(|s| s.to_string()));
    let out = Command::new(env!("CARGO_BIN_EXE_arps-train")).args(&args).output().unwrap();
    assert!(out.status.success(), "arps-train {args:?} failed:\n{}", String::from_utf8_lossy(&out.stderr));
}

/// `arps-train grow|slim --from FROM --run TO [extra]` (a new run made from another's checkpoint).
fn fork(command: &str, from: &Path, to: &Path, extra: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_arps-train"))
        .args([command, "--from", from.to_str().unwrap(), "--run", to.to_str().unwrap()])
        .args(extra)
        .output()
        .unwrap()
}

/// `arps-train export --latest` of `run`, loaded by the engine.
fn export_latest(run: &Path) -> arps::Weights {
    let exported = run.join("latest.safetensors");
    let out = Command::new(env!("CARGO_BIN_EXE_arps-train"))
        .args(["export", "--run", run.to_str().unwrap(), "--latest", "--out", exported.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    arps::Weights::from_bytes(&std::fs::read(&exported).unwrap()).unwrap()
}

const COMMON: [&str; 20] = [
    "--preset",
    "tiny",
    "--batch",
    "4",
    "--lr",
    "3e-3",
    "--warmup-steps",
    "5",
    "--threads",
    "2",
    "--val-pairs",
    "12",
    "--val-every-steps",
    "10",
    "--checkpoint-every-steps",
    "10",
    "--curriculum",
    "off",
    "--quiet",
    "--log-every=10",
];

#[test]
fn short_run_lowers_the_loss_and_exports() {
    let run = dir("short");
    let mut args = COMMON.to_vec();
    args.extend(["--steps", "80"]);
    train(&run, &args);
    let lines = log::read(&run.join("log.jsonl")).unwrap();
    let losses: Vec<f64> =
        lines.iter().filter(|l| l["kind"] == "step").map(|l| l["loss"]["total"].as_f64().unwrap()).collect();
    assert_eq!(losses.len(), 8, "{lines:?}");
    let first = losses[0];
    let last = (losses[6] + losses[7]) / 2.0;
    assert!(last < 0.8 * first, "loss did not drop: {losses:?}");
    assert!(lines.iter().any(|l| l["kind"] == "val" && l["val"]["net_recall"].is_number()));
    let checkpoint::Checkpoint { state: st, params, adam, ema } =
        checkpoint::load(&run.join("checkpoint.safetensors")).unwrap();
    assert!(ema.is_none(), "a run without --ema keeps no average");
    assert_eq!((st.step, st.pairs_seen, adam.t), (80, 320, 80));
    assert_eq!(params.len(), arps::ModelConfig::tiny().tensor_specs().len());
    assert!(run.join("best.safetensors").exists());

    // export (f16) loads in the engine and `arps info` describes it
    let out = run.join("exported.safetensors");
    let e = Command::new(env!("CARGO_BIN_EXE_arps-train"))
        .args(["export", "--run", run.to_str().unwrap(), "--out", out.to_str().unwrap(), "--f16"])
        .output()
        .unwrap();
    assert!(e.status.success(), "{}", String::from_utf8_lossy(&e.stderr));
    let w = arps::Weights::from_bytes(&std::fs::read(&out).unwrap()).unwrap();
    assert_eq!(w.config.preset, "tiny");
    assert!(w.provenance["trainer"].as_str().unwrap().starts_with("arps-train"));
    assert!(w.provenance["pairs_seen"].as_u64().unwrap() > 0);
    let info = Command::new(env!("CARGO_BIN_EXE_arps")).args(["info", out.to_str().unwrap()]).output().unwrap();
    assert!(info.status.success(), "{}", String::from_utf8_lossy(&info.stderr));
    let text = String::from_utf8_lossy(&info.stdout);
    assert!(text.contains("tiny") && text.contains("arps-train"), "{text}");

    // curves
    let svg = run.join("curves.svg");
    let c = Command::new(env!("CARGO_BIN_EXE_arps-train"))
        .args(["curves", "--run", run.to_str().unwrap(), "--out", svg.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(c.status.success(), "{}", String::from_utf8_lossy(&c.stderr));
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<polyline"));
    let _ = std::fs::remove_dir_all(&run);
}

#[test]
fn resume_continues_exactly() {
    let (a, b) = (dir("straight"), dir("resumed"));
    let mut args = COMMON.to_vec();
    args.extend(["--steps", "30", "--ema", "0.9"]);
    train(&a, &args);
    let mut first = COMMON.to_vec();
    first.extend(["--steps", "15", "--ema", "0.9"]);
    train(&b, &first);
    let st = checkpoint::load(&b.join("checkpoint.safetensors")).unwrap().state;
    assert_eq!(st.step, 15);
    // a new run refuses to overwrite an existing one
    let again = Command::new(env!("CARGO_BIN_EXE_arps-train"))
        .args(["train", "--run", b.to_str().unwrap(), "--preset", "tiny", "--steps", "1"])
        .output()
        .unwrap();
    assert!(!again.status.success());
    // stored as the tree stores a run, its log gzipped: the resumed run's log goes on from it
    let plain = b.join("log.jsonl");
    let mut gz = flate2::write::GzEncoder::new(
        std::fs::File::create(log::gz_path(&plain)).unwrap(),
        flate2::Compression::default(),
    );
    std::io::Write::write_all(&mut gz, &std::fs::read(&plain).unwrap()).unwrap();
    gz.finish().unwrap();
    std::fs::remove_file(&plain).unwrap();
    train(&b, &["--resume", "--steps", "30", "--quiet"]);
    assert!(plain.exists() && !log::gz_path(&plain).exists());
    let lines = log::read(&plain).unwrap();
    assert_eq!(lines.iter().filter(|l| l["kind"] == "start").count(), 2, "the first session's lines were lost");
    let checkpoint::Checkpoint { state: sa, params: pa, adam: aa, ema: ea } =
        checkpoint::load(&a.join("checkpoint.safetensors")).unwrap();
    let checkpoint::Checkpoint { state: sb, params: pb, adam: ab, ema: eb } =
        checkpoint::load(&b.join("checkpoint.safetensors")).unwrap();
    assert_eq!((sb.step, sb.pairs_seen, sb.sessions), (30, 120, 2));
    assert_eq!((sa.step, sa.pairs_seen, sa.lr, sa.best_step), (sb.step, sb.pairs_seen, sb.lr, sb.best_step));
    assert_eq!(pa, pb, "parameters differ after resume");
    assert_eq!(aa, ab, "Adam state differs after resume");
    assert!(ea.is_some());
    assert_eq!(ea, eb, "moving average differs after resume");
    let _ = std::fs::remove_dir_all(&a);
    let _ = std::fs::remove_dir_all(&b);
}

#[test]
fn resume_can_fork_with_other_losses_and_lr() {
    let run = dir("fork");
    let mut args = COMMON.to_vec();
    args.extend(["--steps", "10"]);
    train(&run, &args);
    let st = checkpoint::load(&run.join("checkpoint.safetensors")).unwrap().state;
    assert_eq!((st.config.loss.seg, st.config.loss.means), (0.0, 0.0));
    train(&run, &["--resume", "--steps", "20", "--quiet", "--loss", "sup,ctr,seg=0.5,means=0.1", "--lr", "2e-4"]);
    let st = checkpoint::load(&run.join("checkpoint.safetensors")).unwrap().state;
    assert_eq!((st.step, st.config.loss.seg, st.config.loss.means, st.config.loss.sup), (20, 0.5, 0.1, 1.0));
    assert!((st.lr - 2e-4).abs() < 1e-9, "lr {}", st.lr);
    let lines = log::read(&run.join("log.jsonl")).unwrap();
    let steps: Vec<_> = lines.iter().filter(|l| l["kind"] == "step").collect();
    let last = steps.last().unwrap();
    assert!(last["loss"]["seg"].as_f64().unwrap() > 0.0, "{last}");
    let e = last["loss"]["gamma_entropy"].as_f64().unwrap();
    assert!(e > 0.0 && e <= 1.0, "{last}");
    // the partition oracle runs on the run's validation pairs and prints a row per kappa
    let o = Command::new(env!("CARGO_BIN_EXE_arps-train"))
        .args(["partition-oracle", "--run", run.to_str().unwrap(), "--pairs", "4", "--kappa", "8,16"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    let rows: Vec<&str> =
        text.lines().filter(|l| l.trim_start().starts_with("8.0") || l.trim_start().starts_with("16.0")).collect();
    assert_eq!(rows.len(), 2, "{text}");
    // bad overrides are clear errors
    for bad in [["--loss", "sup,nope"], ["--lr", "0"]] {
        let mut a: Vec<&str> = vec!["train", "--run", run.to_str().unwrap(), "--resume", "--steps", "21"];
        a.extend(bad);
        let out = Command::new(env!("CARGO_BIN_EXE_arps-train")).args(&a).output().unwrap();
        assert!(!out.status.success(), "{bad:?} accepted");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("nope") || err.contains("--lr"), "{err}");
    }
    // a fork that fine-tunes at another N and batch size, with another plateau patience; the
    // export carries the N (and training pairs in any pose)
    assert_eq!(st.config.pose_angle_deg, 0.0);
    let (batch, seen) = (st.config.batch, st.pairs_seen);
    let a = [
        "--resume",
        "--steps",
        "25",
        "--quiet",
        "--network-points",
        "24",
        "--patience",
        "7",
        "--pose-angle",
        "180",
        "--batch",
        "3",
        "--val-every-steps",
        "5",
    ];
    let best_before = st.best_score.expect("validated before the fork");
    train(&run, &a);
    let st = checkpoint::load(&run.join("checkpoint.safetensors")).unwrap().state;
    assert_eq!((st.step, st.config.model.n_points, st.config.plateau_patience), (25, 24, 7));
    // the best so far was measured at the old N: the fork's first validation is its best
    assert_eq!(st.best_step, 25, "best {:?} before {best_before}", st.best_score);
    // another batch size from here on: the pair stream goes on where it was
    assert_ne!(batch, 3);
    assert_eq!((st.config.batch, st.pairs_seen), (3, seen + 3 * (25 - 20)));
    assert_eq!(st.config.pose_angle_deg, 180.0);
    let w = export_latest(&run);
    assert_eq!(w.config.n_points, 24);
    let o = Command::new(env!("CARGO_BIN_EXE_arps-train"))
        .args(["partition-oracle", "--run", run.to_str().unwrap(), "--pairs", "2", "--points", "2"])
        .output()
        .unwrap();
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("--points 2"));
    for bad in [["--network-points", "8"], ["--pose-angle", "400"], ["--batch", "0"]] {
        let mut a = vec!["train", "--run", run.to_str().unwrap(), "--resume", "--steps", "26"];
        a.extend(bad);
        let out = Command::new(env!("CARGO_BIN_EXE_arps-train")).args(&a).output().unwrap();
        assert!(!out.status.success(), "{bad:?} accepted");
        assert!(String::from_utf8_lossy(&out.stderr).contains(&bad.join(" ")), "{bad:?}");
    }
    let _ = std::fs::remove_dir_all(&run);
}

#[test]
fn a_new_run_refuses_a_batch_of_zero() {
    let run = dir("batch0");
    let out = Command::new(env!("CARGO_BIN_EXE_arps-train"))
        .args(["train", "--run", run.to_str().unwrap(), "--preset", "tiny", "--steps", "1", "--batch", "0"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--batch 0"), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(!run.join("checkpoint.safetensors").exists());
}

#[test]
fn new_runs_take_model_sizes_and_resumed_runs_keep_theirs() {
    let run = dir("sizes");
    let mut args = COMMON.to_vec();
    args.extend(["--steps", "3", "--feature-dim", "12", "--heads", "3", "--ffn-dim", "20", "--layers", "3"]);
    train(&run, &args);
    // the engine loads the sized model and runs it
    let w = export_latest(&run);
    let c = &w.config;
    assert_eq!((c.feature_dim, c.heads, c.ffn_dim, c.layers), (12, 3, 20, 3));
    assert_eq!(c.preset, "tiny+feature-dim=12+heads=3+ffn-dim=20+layers=3");
    let mut reg = arps::Registrar::new(&w).unwrap();
    let cloud = arps::PointCloud::new(
        (0..200).map(|i| [(i % 10) as f32, (i / 10) as f32 * 0.7, ((i * 7) % 13) as f32 * 0.3]).collect(),
    );
    reg.register(&cloud, &cloud, &arps::Options::default()).unwrap();
    // a resumed run cannot change its size; a new one gets a clear error for an inconsistent one
    let out = Command::new(env!("CARGO_BIN_EXE_arps-train"))
        .args(["train", "--run", run.to_str().unwrap(), "--resume", "--steps", "4", "--layers", "2"])
        .output()
        .unwrap();
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("--layers"));
    let other = dir("sizes-bad");
    let out = Command::new(env!("CARGO_BIN_EXE_arps-train"))
        .args(["train", "--run", other.to_str().unwrap(), "--preset", "tiny", "--steps", "1", "--heads", "5"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("model size") && err.contains("heads = 5"), "{err}");
    let _ = std::fs::remove_dir_all(&run);
    let _ = std::fs::remove_dir_all(&other);
}

#[test]
fn a_moving_average_is_validated_exported_and_can_be_switched_off() {
    let run = dir("ema");
    let mut args = COMMON.to_vec();
    args.extend(["--steps", "20", "--ema", "0.8"]);
    train(&run, &args);
    let ck = checkpoint::load(&run.join("checkpoint.safetensors")).unwrap();
    assert_eq!(ck.state.config.ema_decay, Some(0.8));
    let ema = ck.ema.expect("the checkpoint holds the average");
    assert_eq!(ema.keys().collect::<Vec<_>>(), ck.params.keys().collect::<Vec<_>>());
    assert_ne!(ema, ck.params, "the average lags the parameters");
    // validation scores the average and logs the current parameters beside it
    let lines = log::read(&run.join("log.jsonl")).unwrap();
    let vals: Vec<_> = lines.iter().filter(|l| l["kind"] == "val" && l["step"] == 20).collect();
    assert_eq!(vals.len(), 1, "{lines:?}");
    assert!(vals[0]["val"]["net_recall"].is_number() && vals[0]["val_raw"]["net_recall"].is_number(), "{}", vals[0]);
    // export --latest writes the average
    let w = export_latest(&run);
    for (name, v) in &ema {
        assert_eq!(w.get(name), v.as_slice(), "{name}");
    }
    // a bad decay is a clear error; 0 switches the average off and export writes the parameters
    let bad = Command::new(env!("CARGO_BIN_EXE_arps-train"))
        .args(["train", "--run", run.to_str().unwrap(), "--resume", "--steps", "21", "--ema", "1.5"])
        .output()
        .unwrap();
    assert!(!bad.status.success() && String::from_utf8_lossy(&bad.stderr).contains("--ema 1.5"));
    train(&run, &["--resume", "--steps", "22", "--quiet", "--ema", "0"]);
    let ck = checkpoint::load(&run.join("checkpoint.safetensors")).unwrap();
    assert_eq!((ck.state.step, ck.state.config.ema_decay, ck.ema.is_none()), (22, None, true));
    let w = export_latest(&run);
    for (name, v) in &ck.params {
        assert_eq!(w.get(name), v.as_slice(), "{name}");
    }
    let _ = std::fs::remove_dir_all(&run);
}

/// `export --latest` does not load the shape bank; the bank counts in its provenance are the
/// ones the run's last session logged, not zeros.
#[test]
fn a_latest_export_records_the_bank_the_run_trained_on() {
    let run = dir("bank");
    let bank = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/formats");
    let mut args = COMMON.to_vec();
    args.extend(["--steps", "2", "--bank", bank.to_str().unwrap()]);
    train(&run, &args);
    let log = std::fs::read_to_string(run.join("log.jsonl")).unwrap();
    let start: serde_json::Value =
        serde_json::from_str(log.lines().find(|l| l.contains("\"bank_meshes\"")).unwrap()).unwrap();
    let logged = &start["bank_meshes"];
    assert!(logged["usable"].as_u64().unwrap() > 0, "{logged}");
    let w = export_latest(&run);
    assert_eq!(&w.provenance["data"]["bank_meshes"], logged);
    let _ = std::fs::remove_dir_all(&run);
}

/// The network's estimate (no ICP) on a fixture pair with `w`.
fn network_estimate(w: &arps::Weights) -> nalgebra::Matrix4<f64> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/pairs");
    let s = arps::io::read_path(&root.join("00006_source.ply")).unwrap();
    let t = arps::io::read_path(&root.join("00006_target.ply")).unwrap();
    let mut reg = arps::Registrar::new(w).unwrap();
    let options = arps::Options { icp: arps::IcpKind::Off, ..arps::Options::default() };
    reg.register(&s, &t, &options).unwrap().T_target_source
}

#[test]
fn a_grown_run_computes_what_it_grew_from_and_trains_on() {
    let (base, grown) = (dir("grow-base"), dir("grown"));
    let mut args = COMMON.to_vec();
    args.extend(["--steps", "20", "--ema", "0.9"]);
    train(&base, &args);
    let grow = |from: &Path, to: &Path, ffn: &str| fork("grow", from, to, &["--ffn-dim", ffn]);
    let out = grow(&base, &grown, "40");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));

    let old = checkpoint::load(&base.join("checkpoint.safetensors")).unwrap();
    let new = checkpoint::load(&grown.join("checkpoint.safetensors")).unwrap();
    let (ffn_old, d) = (old.state.config.model.ffn_dim, 2 * old.state.config.model.feature_dim);
    assert_eq!((ffn_old, new.state.config.model.ffn_dim), (16, 40));
    assert_eq!((new.state.step, new.state.pairs_seen, new.adam.t), (old.state.step, old.state.pairs_seen, old.adam.t));
    assert!(new.state.best_score.is_none(), "the smaller network's best is forgotten");
    let w2 = &new.params["layers.0.self_attn.ffn2.weight"];
    assert_eq!(w2.len(), d * 40);
    for r in 0..d {
        assert_eq!(&w2[r * 40..r * 40 + 16], &old.params["layers.0.self_attn.ffn2.weight"][r * 16..(r + 1) * 16]);
        assert!(w2[r * 40 + 16..(r + 1) * 40].iter().all(|&x| x == 0.0), "new units must not reach the output yet");
    }
    let w1 = &new.params["layers.1.cross_attn.ffn1.weight"];
    assert!(w1[16 * d..].iter().any(|&x| x != 0.0), "new units get input weights");
    assert_eq!(new.ema.as_ref().unwrap()["layers.1.cross_attn.ffn1.weight"].len(), 40 * d);
    let v = &new.adam.v["layers.0.self_attn.ffn1.weight"];
    assert!(v[16 * d..].iter().all(|&x| x > 0.0), "new second moments start at their tensor's mean");

    // the engine's forward pass is unchanged
    let (a, b) = (network_estimate(&export_latest(&base)), network_estimate(&export_latest(&grown)));
    assert!((a - b).abs().max() < 1e-6, "{a} vs {b}");

    // it trains on, and the new units start to count
    train(&grown, &["--resume", "--steps", "30", "--quiet"]);
    let trained = checkpoint::load(&grown.join("checkpoint.safetensors")).unwrap();
    assert_eq!(trained.state.step, 30);
    let w2 = &trained.params["layers.0.self_attn.ffn2.weight"];
    assert!((0..d).any(|r| w2[r * 40 + 16..(r + 1) * 40].iter().any(|&x| x != 0.0)));
    assert!(log::read(&grown.join("log.jsonl")).unwrap().iter().any(|l| l["kind"] == "note"));

    // a run is never overwritten, and the width must grow
    let again = grow(&base, &grown, "48");
    assert!(!again.status.success() && String::from_utf8_lossy(&again.stderr).contains("exists"));
    let narrower = grow(&base, &dir("grow-narrower"), "16");
    assert!(!narrower.status.success());
    assert!(String::from_utf8_lossy(&narrower.stderr).contains("must be larger"), "{narrower:?}");
    for d in [base, grown] {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// `slim` keeps one copy of the network (the moving average), exports what the full run exports,
/// and trains on with Adam restarted; it never overwrites a run.
#[test]
fn a_slim_run_exports_what_the_full_run_does_and_trains_on() {
    let (base, slim) = (dir("slim-base"), dir("slim"));
    let mut args = COMMON.to_vec();
    args.extend(["--steps", "20", "--ema", "0.9"]);
    train(&base, &args);
    let out = fork("slim", &base, &slim, &[]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));

    let full = checkpoint::load(&base.join("checkpoint.safetensors")).unwrap();
    let new = checkpoint::load(&slim.join("checkpoint.safetensors")).unwrap();
    assert_eq!(&new.params, full.ema.as_ref().unwrap(), "the moving average becomes the parameters");
    assert!(new.ema.is_none() && new.adam.m.is_empty() && new.adam.v.is_empty());
    assert_eq!((new.adam.t, new.adam.lr), (0, full.adam.lr));
    assert_eq!(
        (new.state.step, new.state.pairs_seen, new.state.best_score),
        (20, full.state.pairs_seen, full.state.best_score)
    );
    let size = |d: &Path| std::fs::metadata(d.join("checkpoint.safetensors")).unwrap().len();
    assert!(size(&slim) * 3 < size(&base), "{} vs {}", size(&slim), size(&base));
    let (a, b) = (export_latest(&base), export_latest(&slim));
    for (name, v) in &a.tensors {
        assert_eq!(b.get(name), v.as_slice(), "{name}");
    }

    // it trains on: the moments fill in again and the average is kept from the parameters
    train(&slim, &["--resume", "--steps", "24", "--quiet"]);
    let trained = checkpoint::load(&slim.join("checkpoint.safetensors")).unwrap();
    assert_eq!((trained.state.step, trained.adam.t), (24, 4));
    assert!(trained.ema.is_some() && trained.adam.v.values().all(|v| v.iter().any(|&x| x > 0.0)));
    assert!(trained.params != new.params);
    assert!(log::read(&slim.join("log.jsonl")).unwrap().iter().any(|l| l["kind"] == "note"));

    let again = fork("slim", &base, &slim, &[]);
    assert!(!again.status.success() && String::from_utf8_lossy(&again.stderr).contains("exists"));
    for d in [base, slim] {
        let _ = std::fs::remove_dir_all(d);
    }
}

#[test]
fn part_whole_pairs_are_a_checked_share_of_a_run() {
    let run = dir("part-whole");
    let init = |share: &str| {
        Command::new(env!("CARGO_BIN_EXE_arps-train"))
            .args(["init", "--run", run.to_str().unwrap(), "--preset", "tiny", "--part-whole", share])
            .output()
            .unwrap()
    };
    let bad = init("1.5");
    assert!(!bad.status.success() && String::from_utf8_lossy(&bad.stderr).contains("--part-whole 1.5"));
    let ok = init("0.25");
    assert!(ok.status.success(), "{}", String::from_utf8_lossy(&ok.stderr));
    let cfg = arps::train::run::session::read_config(&run.join("config.json")).unwrap();
    assert_eq!(cfg.part_whole, 0.25);
    let _ = std::fs::remove_dir_all(&run);
}
