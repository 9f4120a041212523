//! The training-data stream: what the CPU trainer consumes, written in a documented, versioned
//! binary layout so that another trainer (the PyTorch one in `trainer/`) trains on exactly the
//! same pairs, curriculum, network samples and loss targets.
//!
//! Layout, version [`VERSION`], all little-endian:
//!
//! * header: the 8 bytes [`MAGIC`], a `u32` header length `H`, then `H` bytes of JSON
//!   ([`Header`]: format version, `train` or `val`, N, J, batch size, which batches this stream
//!   holds, the record's fields, and the run's [`RunConfig`]);
//! * records, one per pair, each exactly [`Header::record_bytes`] long, fields in the order of
//!   [`Header::fields`] (name, dtype, shape), packed with no padding:
//!
//! | field | dtype | shape | what |
//! |---|---|---|---|
//! | `index` | u64 | [] | stream index of the pair (training: pair `i` of the run's stream; validation: pair `i` of the held-out split) |
//! | `source`, `target` | f32 | [N, 3] | the network's input clouds, engine-normalised units (the engine's network sample) |
//! | `t_gt` | f64 | [4, 4] | ground-truth `T_target_source` between those frames, row-major |
//! | `v_gt_source`, `v_gt_target` | f32 | `[3]` | the shape's centroid, pre-centred on each cloud's mean (the `ctr` target) |
//! | `seg_source`, `seg_target` | f32 | [N, J] | the canonical partition (the `seg` target, the run's `seg_kappa`) |
//! | `corr` | i32 | `[N]` | the consistency correspondences: for source point `i`, its nearest target point under `t_gt` when within the run's `consistency_radius`, else -1 |
//! | `norm_source`, `norm_target` | f64 | [4, 4] | the engine's normalisations, pair units to network frames |
//! | `t_gt_pair` | f64 | [4, 4] | the ground truth in the pair's own units (validation errors) |
//!
//! A training stream holds whole batches: batch `b` is the pairs
//! `first_pair + b * batch .. first_pair + (b + 1) * batch`, and generator `worker` of `workers`
//! writes batches `worker, worker + workers, ...`; reading the workers' streams round-robin gives
//! the CPU trainer's order exactly. A validation stream holds pairs `0..count` of the held-out
//! split with the engine's default sample seed: exactly the pairs `arps-train train` validates on.

use super::data::{to_train_pair, TrainData};
use super::RunConfig;
use crate::train::losses::correspondences;
use crate::train::partition::{self, Role};
use crate::train::Pair as TrainPair;
use nalgebra::Matrix4;
use serde::{Deserialize, Serialize};
use std::io::{Read, Write};

/// First bytes of a stream.
pub const MAGIC: &[u8; 8] = b"ARPSSTRM";
/// Layout version (changes whenever a field changes).
pub const VERSION: u32 = 1;
/// Headers longer than this are refused (a corrupt length cannot allocate without limit).
const MAX_HEADER: u32 = 1 << 20;

/// One field of a record.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Field {
    /// Name.
    pub name: String,
    /// `u64`, `i32`, `f32` or `f64`.
    pub dtype: String,
    /// Shape (empty = scalar).
    pub shape: Vec<usize>,
}

impl Field {
    fn bytes(&self) -> usize {
        let size = match self.dtype.as_str() {
            "u64" | "f64" => 8,
            _ => 4,
        };
        size * self.shape.iter().product::<usize>()
    }
}

/// The fields of a record for `n` points per cloud and `j` Gaussians, in order.
pub fn fields(n: usize, j: usize) -> Vec<Field> {
    let f = |name: &str, dtype: &str, shape: &[usize]| Field {
        name: name.into(),
        dtype: dtype.into(),
        shape: shape.to_vec(),
    };
    vec![
        f("index", "u64", &[]),
        f("source", "f32", &[n, 3]),
        f("target", "f32", &[n, 3]),
        f("t_gt", "f64", &[4, 4]),
        f("v_gt_source", "f32", &[3]),
        f("v_gt_target", "f32", &[3]),
        f("seg_source", "f32", &[n, j]),
        f("seg_target", "f32", &[n, j]),
        f("corr", "i32", &[n]),
        f("norm_source", "f64", &[4, 4]),
        f("norm_target", "f64", &[4, 4]),
        f("t_gt_pair", "f64", &[4, 4]),
    ]
}

/// The stream's header.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// Always `arps-stream`.
    pub format: String,
    /// [`VERSION`].
    pub version: u32,
    /// `train` or `val`.
    pub kind: String,
    /// Points per cloud, N.
    pub n: usize,
    /// Gaussians, J.
    pub j: usize,
    /// Pairs per batch (validation: 1).
    pub batch: usize,
    /// Stream index of the first pair of batch 0.
    pub first_pair: u64,
    /// This generator's number (0-based).
    pub worker: u64,
    /// Generators in all.
    pub workers: u64,
    /// Batches this stream will hold (None: until the reader closes it).
    pub batches: Option<u64>,
    /// Record fields, in order.
    pub fields: Vec<Field>,
    /// The run's configuration (model, losses, data).
    pub config: RunConfig,
}

impl Header {
    /// Bytes per record.
    pub fn record_bytes(&self) -> usize {
        self.fields.iter().map(Field::bytes).sum()
    }
}

/// One record: a training pair and its loss targets.
#[derive(Clone, Debug, PartialEq)]
pub struct Record {
    /// Stream index.
    pub index: u64,
    /// The pair exactly as the CPU trainer consumes it.
    pub pair: TrainPair,
    /// Canonical-partition targets of the source (`[N, J]` row-major).
    pub seg_source: Vec<f32>,
    /// The same for the target.
    pub seg_target: Vec<f32>,
    /// Consistency correspondences (`-1` = none).
    pub corr: Vec<i32>,
    /// Pair units -> source network frame.
    pub norm_source: Matrix4<f64>,
    /// Pair units -> target network frame.
    pub norm_target: Matrix4<f64>,
    /// Ground truth in pair units.
    pub t_gt_pair: Matrix4<f64>,
}

/// The record of a protocol pair `p` with network-sample seed `sample_seed`.
pub fn record(cfg: &RunConfig, index: u64, p: &crate::data::Pair, sample_seed: u64) -> Record {
    let pair = to_train_pair(p, cfg.model.n_points, sample_seed);
    let (j, kappa) = (cfg.model.gaussians, cfg.loss.seg_kappa as f64);
    let seg_source = partition::targets(&pair.source, pair.source_centroid(), &pair.t_gt, Role::Source, j, kappa);
    let seg_target = partition::targets(&pair.target, pair.target_centroid(), &pair.t_gt, Role::Target, j, kappa);
    let mut corr = vec![-1i32; pair.source.len()];
    for (i, k) in correspondences(&pair, cfg.loss.consistency_radius) {
        corr[i] = k as i32;
    }
    let ep = p.engine_frames();
    Record {
        index,
        seg_source,
        seg_target,
        corr,
        norm_source: ep.norm.source_to_normalized(),
        norm_target: ep.norm.target_to_normalized(),
        t_gt_pair: p.T_target_source,
        pair,
    }
}

/// Training record `i` of the run's stream.
pub fn train_record(data: &TrainData, cfg: &RunConfig, i: u64) -> crate::Result<Record> {
    let (p, seed) = data.train_protocol_pair(i)?;
    Ok(record(cfg, i, &p, seed))
}

/// Validation record `i` (the engine's default sample seed, as validation registers it).
pub fn val_record(data: &TrainData, cfg: &RunConfig, i: u64) -> crate::Result<Record> {
    let p = data.val_pair(i)?;
    Ok(record(cfg, i, &p, crate::Options::default().seed))
}

/// Writes the header.
pub fn write_header(w: &mut impl Write, h: &Header) -> std::io::Result<()> {
    let json = serde_json::to_vec(h).map_err(std::io::Error::other)?;
    w.write_all(MAGIC)?;
    w.write_all(&(json.len() as u32).to_le_bytes())?;
    w.write_all(&json)
}

/// Reads and checks a header.
pub fn read_header(r: &mut impl Read) -> Result<Header, String> {
    let mut magic = [0u8; 8];
    r.read_exact(&mut magic).map_err(|e| format!("stream header: {e}"))?;
    if &magic != MAGIC {
        return Err("not an arps stream (bad magic)".into());
    }
    let mut len = [0u8; 4];
    r.read_exact(&mut len).map_err(|e| format!("stream header: {e}"))?;
    let len = u32::from_le_bytes(len);
    if len > MAX_HEADER {
        return Err(format!("stream header of {len} bytes is too long"));
    }
    let mut json = vec![0u8; len as usize];
    r.read_exact(&mut json).map_err(|e| format!("stream header: {e}"))?;
    let h: Header = serde_json::from_slice(&json).map_err(|e| format!("stream header: {e}"))?;
    if h.version != VERSION {
        return Err(format!("stream layout version {} (this build reads {VERSION})", h.version));
    }
    if h.fields != fields(h.n, h.j) {
        return Err("stream fields differ from this build's layout".into());
    }
    Ok(h)
}

fn put_f32(out: &mut Vec<u8>, v: impl IntoIterator<Item = f32>) {
    for x in v {
        out.extend_from_slice(&x.to_le_bytes());
    }
}

fn put_mat(out: &mut Vec<u8>, m: &Matrix4<f64>) {
    for r in 0..4 {
        for c in 0..4 {
            out.extend_from_slice(&m[(r, c)].to_le_bytes());
        }
    }
}

/// Appends a record's bytes (checked against the header's N and J).
pub fn encode(h: &Header, rec: &Record, out: &mut Vec<u8>) -> Result<(), String> {
    let (n, j) = (h.n, h.j);
    let p = &rec.pair;
    if p.source.len() != n || p.target.len() != n || rec.seg_source.len() != n * j || rec.seg_target.len() != n * j {
        return Err(format!("record {} does not have N = {n} points and J = {j}", rec.index));
    }
    out.extend_from_slice(&rec.index.to_le_bytes());
    put_f32(out, p.source.iter().flatten().copied());
    put_f32(out, p.target.iter().flatten().copied());
    put_mat(out, &p.t_gt);
    put_f32(out, p.v_gt_source);
    put_f32(out, p.v_gt_target);
    put_f32(out, rec.seg_source.iter().copied());
    put_f32(out, rec.seg_target.iter().copied());
    for c in &rec.corr {
        out.extend_from_slice(&c.to_le_bytes());
    }
    put_mat(out, &rec.norm_source);
    put_mat(out, &rec.norm_target);
    put_mat(out, &rec.t_gt_pair);
    Ok(())
}

/// Reads one record (None at a clean end of stream).
pub fn read_record(r: &mut impl Read, h: &Header) -> Result<Option<Record>, String> {
    let mut buf = vec![0u8; h.record_bytes()];
    let mut got = 0;
    while got < buf.len() {
        match r.read(&mut buf[got..]) {
            Ok(0) if got == 0 => return Ok(None),
            Ok(0) => return Err(format!("stream ends inside a record ({got} of {} bytes)", buf.len())),
            Ok(k) => got += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(format!("stream: {e}")),
        }
    }
    let mut at = 0usize;
    let mut take = |k: usize| {
        let s = &buf[at..at + k];
        at += k;
        s
    };
    let (n, j) = (h.n, h.j);
    let u64v = |b: &[u8]| u64::from_le_bytes(b.try_into().unwrap_or([0; 8]));
    let f32s =
        |b: &[u8]| -> Vec<f32> { b.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect() };
    let mat = |b: &[u8]| -> Matrix4<f64> {
        let v: Vec<f64> = b.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8]))).collect();
        Matrix4::from_fn(|r, c| v[r * 4 + c])
    };
    let pts = |v: Vec<f32>| -> Vec<[f32; 3]> { v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect() };
    let index = u64v(take(8));
    let source = pts(f32s(take(n * 12)));
    let target = pts(f32s(take(n * 12)));
    let t_gt = mat(take(128));
    let vs = f32s(take(12));
    let vt = f32s(take(12));
    let seg_source = f32s(take(n * j * 4));
    let seg_target = f32s(take(n * j * 4));
    let corr = take(n * 4).chunks_exact(4).map(|c| i32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
    let norm_source = mat(take(128));
    let norm_target = mat(take(128));
    let t_gt_pair = mat(take(128));
    Ok(Some(Record {
        index,
        pair: TrainPair {
            source,
            target,
            t_gt,
            v_gt_source: [vs[0], vs[1], vs[2]],
            v_gt_target: [vt[0], vt[1], vt[2]],
        },
        seg_source,
        seg_target,
        corr,
        norm_source,
        norm_target,
        t_gt_pair,
    }))
}

/// What [`write_stream`] writes.
#[derive(Clone, Debug)]
pub struct StreamSpec {
    /// `train` (batches of the training stream) or `val` (held-out pairs `0..count`).
    pub val: bool,
    /// Training: stream index of the first pair of batch 0 (a resumed run's `pairs_seen`).
    pub first_pair: u64,
    /// This generator's number.
    pub worker: u64,
    /// Generators in all.
    pub workers: u64,
    /// Training: batches to write (None = until the reader closes the stream); validation: pairs.
    pub count: Option<u64>,
}

/// The header of a stream.
pub fn header(cfg: &RunConfig, spec: &StreamSpec) -> Header {
    let (n, j) = (cfg.model.n_points, cfg.model.gaussians);
    Header {
        format: "arps-stream".into(),
        version: VERSION,
        kind: if spec.val { "val" } else { "train" }.into(),
        n,
        j,
        batch: if spec.val { 1 } else { cfg.batch.max(1) },
        first_pair: if spec.val { 0 } else { spec.first_pair },
        worker: spec.worker,
        workers: spec.workers,
        batches: spec.count,
        fields: fields(n, j),
        config: cfg.clone(),
    }
}

/// Writes a stream: the header, then the records, batch by batch (the pairs of a batch are built
/// on `pool`). A reader that closes the stream ends it without an error.
pub fn write_stream(
    w: &mut impl Write,
    pool: &rayon::ThreadPool,
    data: &TrainData,
    cfg: &RunConfig,
    spec: &StreamSpec,
) -> Result<(), String> {
    use rayon::prelude::*;
    if spec.workers == 0 || spec.worker >= spec.workers {
        return Err(format!("worker {} of {}: expected 0 <= worker < workers", spec.worker, spec.workers));
    }
    if spec.val && spec.count.is_none() {
        return Err("a validation stream needs a count".into());
    }
    let h = header(cfg, spec);
    let closed = |e: &std::io::Error| e.kind() == std::io::ErrorKind::BrokenPipe;
    match write_header(w, &h) {
        Err(e) if closed(&e) => return Ok(()),
        r => r.map_err(|e| format!("stream: {e}"))?,
    }
    let mut buf = Vec::new();
    let mut b = spec.worker;
    let mut written = 0u64;
    loop {
        if spec.count.is_some_and(|c| written >= c) {
            break;
        }
        let indices: Vec<u64> = if spec.val {
            let count = spec.count.unwrap_or(0);
            written = count;
            (0..count).collect()
        } else {
            let first = spec.first_pair + b * h.batch as u64;
            (first..first + h.batch as u64).collect()
        };
        let recs = pool
            .install(|| {
                indices
                    .par_iter()
                    .map(|&i| if spec.val { val_record(data, cfg, i) } else { train_record(data, cfg, i) })
                    .collect::<crate::Result<Vec<_>>>()
            })
            .map_err(|e| format!("pair: {e}"))?;
        buf.clear();
        for r in &recs {
            encode(&h, r, &mut buf)?;
        }
        match w.write_all(&buf).and_then(|_| w.flush()) {
            Err(e) if closed(&e) => return Ok(()),
            r => r.map_err(|e| format!("stream: {e}"))?,
        }
        if !spec.val {
            written += 1;
            b += spec.workers;
        }
    }
    Ok(())
}
