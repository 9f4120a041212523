//! The engine's budgets: how large an input may be, checked before any work proportional to it.
//!
//! WebAssembly (wasm32) has at most 4 GiB of linear memory, and memory once grown is never given
//! back, so one oversized call would leave the page (or the worker) crippled, and a failed
//! allocation is a trap, not an error. Every input is therefore checked against these limits
//! before anything proportional to it is allocated, and an oversized one gets an
//! [`Error::TooLarge`] naming the limit, the input's size, and how to make it fit.
//!
//! | budget | value | what it bounds |
//! | --- | --- | --- |
//! | [`MAX_CALL_BYTES`] | 2 GiB | memory one call may use (half of wasm32's 4 GiB: the rest is for the model, the caller's copies, and fragmentation) |
//! | [`REGISTER_BYTES_PER_POINT`] | 128 B | peak memory of a registration per input point (measured natively, see below) |
//! | [`MAX_POINTS_PER_CLOUD`] | 8,000,000 | points per cloud given to a registration: `MAX_CALL_BYTES / (2 x REGISTER_BYTES_PER_POINT)`, rounded down |
//! | [`MAX_FILE_POINTS`] | 8,000,000 | points (vertices) a file may hold for the readers (the same figure: a cloud that cannot be registered is not worth decoding) |
//! | [`MAX_DECODED_BYTES`] | 1 GiB | bytes a compressed body (PCD `binary_compressed`) may decompress to |
//! | [`MAX_MODEL_DIM`] | 4,096 | every size in a model config (N, C, heads, hidden widths, H, J) |
//! | [`MAX_MODEL_LIST`] | 16 | entries of a config's hidden-width lists (`pos_hidden`, `head_hidden`) |
//! | [`MAX_MODEL_LAYERS`] | 16 | ARPS layers L |
//! | [`MAX_MODEL_PARAMETERS`] | 33,554,432 | parameters of a model (128 MiB as f32; the paper-size model has 13.8M) |
//! | [`MAX_MODEL_CONFIG_BYTES`] | 65,536 | bytes of a weights file's `config` JSON |
//!
//! **Where 128 bytes per point comes from.** A registration holds, per input point, the caller's
//! cloud (12 B), the validated copy (12 B), the turned copy when an initial rotation is given
//! (12 B), the normalised copy (12 B), the voxel grid's sort keys while it runs (32 B natively,
//! 28 B on wasm32), and the ICP cloud and its kd-tree and normals when voxelisation is off
//! (up to 40 B): 120 B, rounded up to 128 B. Measured natively (peak RSS of `arps register` on
//! synthetic binary PLY pairs with default options, reading included; `BENCHMARK.md`, "Memory"),
//! the peak grows by 53 B per input point; in WebAssembly the binding's copies of the caller's
//! arrays add 24 B, and `voxelSize: 0` (ICP on the full clouds) adds the kd-tree and normals.
//! The issue that set these budgets saw 2 GB of wasm memory at 10M points per cloud (100 B per
//! point) and a trap at 20M.
//!
//! A cloud over the limit should be downsampled before it is registered, e.g. on a voxel grid
//! ([`crate::sampling::voxel_downsample`]); the `voxelSize` option thins only the clouds ICP
//! uses, after the inputs are loaded, so it does not lift this limit.

use crate::{Error, Result};

/// Memory one call may use, in bytes: half of wasm32's 4 GiB.
pub const MAX_CALL_BYTES: u64 = 2 << 30;

/// Peak memory of a registration per input point, in bytes (see the module docs).
pub const REGISTER_BYTES_PER_POINT: u64 = 128;

/// Most points per cloud a registration accepts: `MAX_CALL_BYTES / (2 * REGISTER_BYTES_PER_POINT)`
/// (8,388,608), rounded down to 8,000,000.
pub const MAX_POINTS_PER_CLOUD: usize = 8_000_000;

/// Most points (vertices) the readers decode from one file.
pub const MAX_FILE_POINTS: usize = MAX_POINTS_PER_CLOUD;

/// Most bytes a compressed body may decompress to.
pub const MAX_DECODED_BYTES: u64 = 1 << 30;

/// Largest value of every size in a model config (points, widths, heads, H, J).
pub const MAX_MODEL_DIM: usize = 4096;

/// Most entries in a model config's hidden-width lists.
pub const MAX_MODEL_LIST: usize = 16;

/// Most ARPS layers in a model.
pub const MAX_MODEL_LAYERS: usize = 16;

/// Most parameters in a model.
pub const MAX_MODEL_PARAMETERS: u64 = 32 << 20;

/// Most bytes of a weights file's `config` JSON.
pub const MAX_MODEL_CONFIG_BYTES: usize = 64 << 10;

// The per-cloud limit must fit the call budget with both clouds.
const _: () = assert!(2 * MAX_POINTS_PER_CLOUD as u64 * REGISTER_BYTES_PER_POINT <= MAX_CALL_BYTES);

/// Fails with [`Error::TooLarge`] when a cloud given to a registration has more than
/// [`MAX_POINTS_PER_CLOUD`] points; `what` names it (`"source"`, `"target"`).
pub fn check_cloud_points(what: &str, n: usize) -> Result<()> {
    if n <= MAX_POINTS_PER_CLOUD {
        return Ok(());
    }
    Err(Error::TooLarge(format!(
        "{what} has {n} points, more than the {MAX_POINTS_PER_CLOUD} a registration accepts per cloud \
         (about {REGISTER_BYTES_PER_POINT} bytes per point, within {} MiB per call, for WebAssembly's 4 GiB memory): \
         downsample it first, e.g. on a voxel grid (a voxel about {:.2}x the mean point spacing keeps about \
         {MAX_POINTS_PER_CLOUD} points); the voxelSize option thins only ICP's copy and does not lift this limit",
        MAX_CALL_BYTES >> 20,
        voxel_factor(n),
    )))
}

/// Fails with [`Error::TooLarge`] when a file declares or holds more than [`MAX_FILE_POINTS`]
/// points; `format` names the reader.
pub fn check_file_points(format: &str, n: u64) -> Result<()> {
    if n <= MAX_FILE_POINTS as u64 {
        return Ok(());
    }
    Err(Error::TooLarge(format!(
        "the {format} file holds {n} points, more than the {MAX_FILE_POINTS} the readers accept \
         (a registration takes at most {MAX_POINTS_PER_CLOUD} per cloud, for WebAssembly's 4 GiB memory): \
         downsample it before loading (e.g. a voxel grid in CloudCompare, PDAL or Open3D)"
    )))
}

/// How much coarser than the mean spacing a voxel grid must be to bring a surface scan of `n`
/// points down to [`MAX_POINTS_PER_CLOUD`] (points on a surface scale with the area, so with the
/// square of the spacing).
fn voxel_factor(n: usize) -> f64 {
    (n as f64 / MAX_POINTS_PER_CLOUD as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_accept_up_to_and_refuse_beyond() {
        assert!(check_cloud_points("source", MAX_POINTS_PER_CLOUD).is_ok());
        let e = check_cloud_points("source", 20_000_000).unwrap_err().to_string();
        assert!(e.contains("20000000") && e.contains("8000000") && e.contains("voxel"), "{e}");
        assert!(check_file_points("PLY", MAX_FILE_POINTS as u64 + 1).is_err());
        assert!(check_file_points("PLY", 10).is_ok());
    }
}
