//! `arps quantize IN OUT --bits 8`: rewrites a weights file at another precision (int8 with a
//! scale per row, f16 or f32) and reports the sizes and the largest change of any weight.

use arps::{StoreAs, Weights};
use clap::Args;
use std::path::PathBuf;

/// Arguments of `arps quantize`.
#[derive(Args)]
pub struct QuantizeArgs {
    /// Weights file to read (any precision).
    input: PathBuf,
    /// Weights file to write.
    output: PathBuf,
    /// Bits per weight: 8 (int8 weight matrices with an f32 scale per row, f16 vectors), 16 (f16)
    /// or 32 (f32).
    #[arg(long, default_value_t = 8)]
    bits: u32,
}

/// Runs `arps quantize`.
pub fn run(args: QuantizeArgs) -> Result<(), String> {
    let store = match args.bits {
        8 => StoreAs::I8,
        16 => StoreAs::F16,
        32 => StoreAs::F32,
        b => return Err(format!("--bits {b} is not supported: use 8 (int8), 16 (f16) or 32 (f32)")),
    };
    let in_bytes = arps::io::read_file(&args.input).map_err(|e| e.to_string())?;
    let mut w = Weights::from_bytes(&in_bytes).map_err(|e| format!("{}: {e}", args.input.display()))?;
    let storage = match store {
        StoreAs::I8 => "int8 weight matrices (symmetric, one f32 scale per row), f16 vectors",
        StoreAs::F16 => "f16",
        StoreAs::F32 => "f32",
    };
    let note = serde_json::json!({ "storage": storage, "by": "arps quantize", "bits": args.bits });
    match &mut w.provenance {
        serde_json::Value::Object(map) => {
            map.insert("quantized".to_string(), note);
            // `stored_as` (written by the trainer's export) names how the weights are stored now.
            let stored_as = match store {
                StoreAs::I8 => "int8",
                StoreAs::F16 => "f16",
                StoreAs::F32 => "f32",
            };
            map.insert("stored_as".to_string(), serde_json::json!(stored_as));
        }
        other => *other = serde_json::json!({ "original": other.take(), "quantized": note }),
    }
    let bytes = w.to_bytes(store).map_err(|e| e.to_string())?;
    // Read back what was written: the file must load, and say how far each tensor moved.
    let back = Weights::from_bytes(&bytes).map_err(|e| format!("internal: the written file does not load: {e}"))?;
    let (mut worst, mut worst_name) = (0.0f32, String::new());
    for (name, v) in &w.tensors {
        let scale = v.iter().fold(0.0f32, |m, x| m.max(x.abs())).max(f32::MIN_POSITIVE);
        let err = v.iter().zip(&back.tensors[name]).fold(0.0f32, |m, (a, b)| m.max((a - b).abs())) / scale;
        if err > worst {
            (worst, worst_name) = (err, name.clone());
        }
    }
    std::fs::write(&args.output, &bytes).map_err(|e| format!("{}: {e}", args.output.display()))?;
    out!(
        "wrote {} ({} bytes, was {} bytes; {storage}); largest change {:.2e} of a tensor's largest magnitude ({})",
        args.output.display(),
        bytes.len(),
        in_bytes.len(),
        worst,
        if worst_name.is_empty() { "none" } else { &worst_name }
    );
    Ok(())
}
