#![cfg(feature = "train")]
//! The training-data stream (`arps::train::run::stream`) and the packed bank: records read back
//! equal what the CPU trainer builds for the same seed and index (pair, canonical partition,
//! correspondences), workers split batches round-robin, the validation stream holds the
//! validation pairs, broken streams are refused, and a packed bank round-trips.

mod common;
use arps::data::bank::{Bank, NamedMesh};
use arps::io::Mesh;
use arps::train::losses::correspondences;
use arps::train::partition::{self, Role};
use arps::train::run::data::{to_train_pair, TrainData};
use arps::train::run::stream::{self, StreamSpec};
use arps::train::run::{bank_pack, Curriculum, RunConfig};
use arps::train::LossConfig;
use arps::ModelConfig;

fn config() -> RunConfig {
    RunConfig {
        model: ModelConfig::tiny(),
        loss: LossConfig { seg_kappa: 4.0, consistency_radius: 0.08, ..LossConfig::default() },
        batch: 3,
        lr: 1e-3,
        warmup_steps: 10,
        clip_norm: Some(1.0),
        plateau_patience: 3,
        min_lr: 1e-5,
        seed: 5,
        threads: 1,
        bank: None,
        val_fraction: 0.15,
        bank_fraction: 0.3,
        pair_points: 256,
        curriculum: Curriculum::default(),
        pose_angle_deg: 0.0,
        part_whole: 0.0,
        ema_decay: None,
        val_pairs: 4,
        val_every_minutes: 5.0,
        val_every_steps: None,
        icp_every_validations: 0,
        checkpoint_every_minutes: 3.0,
        checkpoint_every_steps: None,
        log_every_steps: 10,
    }
}

fn pool() -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap()
}

fn write(cfg: &RunConfig, spec: &StreamSpec) -> Vec<u8> {
    let data = TrainData::new(cfg).unwrap();
    let mut out = Vec::new();
    stream::write_stream(&mut out, &pool(), &data, cfg, spec).unwrap();
    out
}

fn read_all(bytes: &[u8]) -> (stream::Header, Vec<stream::Record>) {
    let mut r = bytes;
    let h = stream::read_header(&mut r).unwrap();
    let mut recs = Vec::new();
    while let Some(rec) = stream::read_record(&mut r, &h).unwrap() {
        recs.push(rec);
    }
    (h, recs)
}

#[test]
fn training_records_are_what_the_cpu_trainer_builds() {
    let cfg = config();
    let spec = StreamSpec { val: false, first_pair: 30, worker: 1, workers: 2, count: Some(2) };
    let bytes = write(&cfg, &spec);
    let (h, recs) = read_all(&bytes);
    assert_eq!((h.n, h.j, h.batch, h.kind.as_str()), (32, 4, 3, "train"));
    assert_eq!(h.config, cfg);
    assert_eq!(bytes.len(), 12 + serde_json::to_vec(&h).unwrap().len() + 6 * h.record_bytes());
    // worker 1 of 2 holds batches 1 and 3 of the stream that starts at pair 30
    let indices: Vec<u64> = recs.iter().map(|r| r.index).collect();
    assert_eq!(indices, vec![33, 34, 35, 39, 40, 41]);
    let data = TrainData::new(&cfg).unwrap();
    let j = cfg.model.gaussians;
    for r in &recs {
        let want = data.train_pair(r.index).unwrap();
        assert_eq!(r.pair, want, "pair {}", r.index);
        let seg_s = partition::targets(&want.source, want.source_centroid(), &want.t_gt, Role::Source, j, 4.0);
        let seg_t = partition::targets(&want.target, want.target_centroid(), &want.t_gt, Role::Target, j, 4.0);
        assert_eq!(r.seg_source, seg_s);
        assert_eq!(r.seg_target, seg_t);
        let mut corr = vec![-1; want.source.len()];
        for (i, k) in correspondences(&want, 0.08) {
            corr[i] = k as i32;
        }
        assert!(corr.iter().any(|&c| c >= 0), "pair {} has no correspondences", r.index);
        assert_eq!(r.corr, corr);
        // the normalisations map the pair's ground truth onto the network frames' ground truth
        let mapped = r.norm_target * r.t_gt_pair * r.norm_source.try_inverse().unwrap();
        assert!((mapped - r.pair.t_gt).abs().max() < 1e-9);
    }
    // the other worker's batches interleave to the whole stream
    let (_, other) = read_all(&write(&cfg, &StreamSpec { worker: 0, ..spec.clone() }));
    assert_eq!(other.iter().map(|r| r.index).collect::<Vec<_>>(), vec![30, 31, 32, 36, 37, 38]);
}

#[test]
fn validation_records_are_the_validation_pairs() {
    let cfg = config();
    let (h, recs) =
        read_all(&write(&cfg, &StreamSpec { val: true, first_pair: 0, worker: 0, workers: 1, count: Some(4) }));
    assert_eq!((h.kind.as_str(), h.batch, recs.len()), ("val", 1, 4));
    let data = TrainData::new(&cfg).unwrap();
    for (i, r) in recs.iter().enumerate() {
        let p = data.val_pair(i as u64).unwrap();
        assert_eq!(r.index, i as u64);
        assert_eq!(r.pair, to_train_pair(&p, 32, arps::Options::default().seed));
        assert_eq!(r.t_gt_pair, p.T_target_source);
    }
}

#[test]
fn broken_streams_are_refused() {
    let cfg = config();
    let bytes = write(&cfg, &StreamSpec { val: false, first_pair: 0, worker: 0, workers: 1, count: Some(1) });
    let mut bad = bytes.clone();
    bad[0] = b'X';
    assert!(stream::read_header(&mut bad.as_slice()).unwrap_err().contains("magic"));
    let cut = &bytes[..bytes.len() - 5];
    let mut r = cut;
    let h = stream::read_header(&mut r).unwrap();
    let mut result = Ok(None);
    for _ in 0..4 {
        result = stream::read_record(&mut r, &h);
        if !matches!(result, Ok(Some(_))) {
            break;
        }
    }
    assert!(result.unwrap_err().contains("inside a record"), "a record cut short is an error");
    let data = TrainData::new(&cfg).unwrap();
    let e = stream::write_stream(
        &mut Vec::new(),
        &pool(),
        &data,
        &cfg,
        &StreamSpec { val: false, first_pair: 0, worker: 2, workers: 2, count: Some(1) },
    )
    .unwrap_err();
    assert!(e.contains("worker"), "{e}");
}

fn tetra_box(s: f32) -> Mesh {
    let v = [[0.0, 0.0, 0.0], [s, 0.0, 0.0], [0.0, s, 0.0], [0.0, 0.0, s], [s, s, s * 0.5]];
    Mesh { vertices: v.to_vec(), triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3], [1, 4, 2], [2, 4, 3]] }
}

#[test]
fn packed_bank_round_trips() {
    let bank = Bank {
        meshes: vec![
            NamedMesh { name: "a/one.off".into(), mesh: tetra_box(1.0) },
            NamedMesh { name: "b/two.ply".into(), mesh: tetra_box(2.5) },
        ],
        skipped: vec![arps::data::bank::Skipped { name: "c/flat.obj".into(), reason: "flat".into() }],
    };
    let mut bytes = Vec::new();
    bank_pack::write(&bank, &mut bytes).unwrap();
    let back = bank_pack::read(bytes.as_slice()).unwrap();
    assert_eq!(back.meshes.len(), 2);
    for (a, b) in back.meshes.iter().zip(&bank.meshes) {
        assert_eq!((&a.name, &a.mesh), (&b.name, &b.mesh));
    }
    assert_eq!(back.skipped, bank.skipped);
    assert!(bank_pack::read(&bytes[..bytes.len() / 2]).is_err(), "a truncated pack is an error");
    assert!(bank_pack::read(&b"not gzip"[..]).is_err());
}

#[test]
fn gzipped_logs_read_like_plain_ones() {
    use arps::train::run::log;
    use std::io::Write;
    let dir = common::scratch("gz-log");
    std::fs::create_dir_all(&dir).unwrap();
    let text = "{\"kind\":\"start\",\"step\":0}\nnot json\n{\"kind\":\"end\",\"step\":5}\n";
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    gz.write_all(text.as_bytes()).unwrap();
    std::fs::write(dir.join("log.jsonl.gz"), gz.finish().unwrap()).unwrap();
    let lines = log::read(&dir.join("log.jsonl")).unwrap();
    assert_eq!(lines.len(), 2);
    assert_eq!(lines[1]["step"], 5);
    // a plain log wins over a gzipped one
    std::fs::write(dir.join("log.jsonl"), "{\"kind\":\"start\",\"step\":7}\n").unwrap();
    assert_eq!(log::read(&dir.join("log.jsonl")).unwrap()[0]["step"], 7);
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(log::read(&dir.join("log.jsonl")).is_err(), "no log at all is an error");
    // a finished run's committed log
    let committed =
        log::read(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models/runs/web-1/log.jsonl")).unwrap();
    assert!(committed.iter().filter(|l| l["kind"] == "val").count() > 5);
}

#[test]
fn a_share_of_the_pairs_can_be_a_part_against_the_whole_shape() {
    use arps::train::run::data::{part_of_whole, PART_KEEP};
    let distinct = |idx: &[u32]| idx.iter().copied().collect::<std::collections::HashSet<u32>>().len();
    // as many points per cloud as the dense sample has: a crop's samples are then all its points
    let base = RunConfig { pair_points: 4096, ..config() };
    let protocol = TrainData::new(&base).unwrap();
    let whole = TrainData::new(&RunConfig { part_whole: 1.0, ..base.clone() }).unwrap();
    let quarter = TrainData::new(&RunConfig { part_whole: 0.25, ..base }).unwrap();
    let mut parts = 0;
    for i in [0u64, 1, 2, 3, 4, 5, 6, 7, 40_000] {
        let (a, _) = protocol.train_protocol_pair(i).unwrap();
        let (b, _) = whole.train_protocol_pair(i).unwrap();
        // the protocol crops 70-85% of the shape for both; a part is 30-60% of it against all of it
        assert!(distinct(&a.target_dense_index) < 3_500, "pair {i}");
        let (sb, tb) = (distinct(&b.source_dense_index), distinct(&b.target_dense_index));
        assert!(sb <= 2_458 && tb == 4_096 && b.overlap == 1.0, "pair {i}: {sb} / {tb}, overlap {}", b.overlap);
        let (c, _) = quarter.train_protocol_pair(i).unwrap();
        if part_of_whole(protocol.stream.wrapping_add(i), 0.25).is_some() {
            parts += 1;
            assert_eq!(c.target_dense_index, b.target_dense_index, "pair {i}");
        } else {
            assert_eq!((c.source, c.target), (a.source, a.target), "pair {i}: the protocol's pair");
        }
    }
    assert!(parts > 0 && parts < 9, "{parts} of 9 pairs were parts");
    // by the hash, about the share asked for, and the source's share within its range
    let drawn: Vec<f64> = (0..4_000u64).filter_map(|i| part_of_whole(i, 0.25)).collect();
    assert!((900..1_100).contains(&drawn.len()), "{} of 4,000", drawn.len());
    assert!(drawn.iter().all(|k| (PART_KEEP.0..PART_KEEP.1).contains(k)));
    assert!(part_of_whole(7, 0.0).is_none());
}
