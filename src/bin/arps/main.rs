//! `arps`: register two point clouds from the command line, list an E57 file's scans, describe or
//! quantise a weights file, or benchmark the pipeline.
//!
//! Errors print one line on stderr (`arps: ...`) and exit with status 1 (2 for usage errors).

use arps::{ModelConfig, Registrar, StoreAs, Weights};
use clap::{Parser, Subcommand};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[macro_use]
#[path = "../common/out.rs"]
mod out;
mod bench;
mod compare;
mod eval;
mod make_pairs;
mod quantize;
mod register;

#[derive(Parser)]
#[command(name = "arps", version, about = "Partial-to-partial point-cloud registration (DGMR-ARPS + ICP)")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Register each SOURCE onto TARGET and print its T_target_source (maps source points into the
    /// target frame). Several sources are registered in turn onto the target read once (and, where
    /// it is at least as large as they are, prepared once).
    Register(register::RegisterArgs),
    /// List the scans of an E57 file (index, name, point records), to choose one with
    /// `register --source-scan K` / `--target-scan K`; a file of another format holds one cloud.
    Scans {
        /// The point-cloud file.
        file: PathBuf,
        /// Print one JSON array of `{ "name", "records" }` (what the JS API's `listScans` gives).
        #[arg(long)]
        json: bool,
    },
    /// Describe a weights file: config, parameter count, provenance.
    Info {
        /// Weights file (safetensors).
        weights: PathBuf,
    },
    /// Time each stage (read, downsample, network, GMR, ICP) on a 1024 + 1024-point pair and compare the
    /// network's GFLOP/s with the matmul peak measured in the same run.
    Bench(bench::BenchArgs),
    /// Evaluate a pair set (pairs.tsv) side by side: network, network + ICP, network + multi-start ICP (the
    /// default), multi-start ICP without the network, ICP from identity, ICP from centroids, untrained
    /// network + ICP, FPFH + RANSAC + ICP, FPFH + RANSAC + network + ICP, the exhaustive multi-start
    /// search; prints MRE, MTE, Recall, RRE, RTE, ms/pair.
    Eval(eval::EvalArgs),
    /// Compare two `arps eval --json` results on the same pairs: recall, the pairs only one side
    /// registers, and an exact McNemar p-value, per method.
    Compare(compare::CompareArgs),
    /// Write a pair set made with the paper's protocol (PLY files, pairs.tsv, pairs.json).
    MakePairs(make_pairs::MakePairsArgs),
    /// Rewrite a weights file at another precision: `--bits 8` (int8 with a scale per row, about a
    /// quarter of f32), 16 (f16) or 32 (f32).
    Quantize(quantize::QuantizeArgs),
    /// Write deterministic random (untrained) weights for a preset; for development and tests.
    RandomWeights {
        /// Preset: web, paper or tiny.
        #[arg(long, default_value = "web")]
        preset: String,
        /// Seed.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Store as f16 (half the size).
        #[arg(long)]
        f16: bool,
        /// Output path.
        #[arg(long)]
        out: PathBuf,
    },
}

/// Exit status of an error (an unreadable file, a bad option, a failed source), as clap's for a
/// mistyped flag; `register --min-confidence` exits 1 ([`register::UNSURE`]) when every source
/// was registered but some answer is below it, so a batch tells "check by hand" from "failed".
const ERROR: u8 = 2;

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli.command) {
        Ok(Some(unsure)) => {
            eprintln!("arps: {unsure}");
            ExitCode::from(register::UNSURE)
        }
        Ok(None) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("arps: {e}");
            ExitCode::from(ERROR)
        }
    }
}

/// The weights at `path`, or the embedded default model.
pub(crate) fn load_registrar(path: Option<&Path>) -> Result<Registrar, String> {
    match path {
        Some(p) => {
            let bytes = arps::io::read_file(p).map_err(|e| e.to_string())?;
            Registrar::from_bytes(&bytes).map_err(|e| format!("{}: {e}", p.display()))
        }
        None => Registrar::with_default_model().map_err(|e| e.to_string()),
    }
}

/// Runs the command: `Some(why)` when it ran but some answer is below `register`'s
/// `--min-confidence`.
fn run(command: Command) -> Result<Option<String>, String> {
    let done = match command {
        Command::Register(args) => return register::run(args),
        Command::Info { weights } => {
            let bytes = arps::io::read_file(&weights).map_err(|e| e.to_string())?;
            let w = Weights::from_bytes(&bytes).map_err(|e| format!("{}: {e}", weights.display()))?;
            let c = &w.config;
            out!("{}: arps weights, format version {}", weights.display(), arps::weights::FORMAT_VERSION);
            out!("  file size     {} bytes", bytes.len());
            out!("  parameters    {}", c.parameter_count());
            out!("  preset        {}", c.preset);
            out!(
                "  network       N = {}, C = {} (tokens {}), heads {}, FFN {}, layers {}, J = {}",
                c.n_points,
                c.feature_dim,
                c.token_dim(),
                c.heads,
                c.ffn_dim,
                c.layers,
                c.gaussians
            );
            out!("  reference     {:?} (top_h {}, temperature {})", c.reference, c.top_h, c.soft_temperature);
            out!("  pos MLP       3 -> {:?} -> {}", c.pos_hidden, c.feature_dim);
            out!("  head          {} -> {:?} -> {}", 2 * c.feature_dim, c.head_hidden, c.gaussians);
            out!(
                "  provenance    {}",
                serde_json::to_string_pretty(&w.provenance).unwrap_or_default().replace('\n', "\n                ")
            );
            Ok(())
        }
        Command::Scans { file, json } => {
            let bytes = arps::io::read_file(&file).map_err(|e| e.to_string())?;
            let scans = arps::io::list_scans(&bytes, &arps::io::file_name(&file))
                .map_err(|e| format!("{}: {e}", file.display()))?;
            if json {
                out!("{}", serde_json::to_string(&scans).map_err(|e| e.to_string())?);
            } else if scans.is_empty() {
                out!("{}: one cloud (only E57 files hold several scans)", file.display());
            } else {
                for (k, s) in scans.iter().enumerate() {
                    out!("{k}  {}  {} points", s.name.as_deref().unwrap_or("(no name)"), s.records);
                }
            }
            Ok(())
        }
        Command::Bench(args) => bench::run(args),
        Command::Eval(args) => eval::run(args),
        Command::Compare(args) => compare::run(args),
        Command::MakePairs(args) => make_pairs::run(args),
        Command::Quantize(args) => quantize::run(args),
        Command::RandomWeights { preset, seed, f16, out } => {
            let config = ModelConfig::preset(&preset).map_err(|e| e.to_string())?;
            let w = Weights::random(&config, seed).map_err(|e| e.to_string())?;
            let bytes = w.to_bytes(if f16 { StoreAs::F16 } else { StoreAs::F32 }).map_err(|e| e.to_string())?;
            std::fs::write(&out, &bytes).map_err(|e| format!("{}: {e}", out.display()))?;
            out!("wrote {} ({} bytes, {} parameters)", out.display(), bytes.len(), config.parameter_count());
            Ok(())
        }
    };
    done.map(|()| None)
}

/// `--up x,y,z` as the option's three numbers (the engine checks them further).
pub(crate) fn up_axis(v: &[f64]) -> Result<[f64; 3], String> {
    match v {
        &[x, y, z] => Ok([x, y, z]),
        _ => Err(format!("--up: expected three numbers x,y,z, got {}", v.len())),
    }
}
