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
//! | [`INPUT_BYTES_PER_POINT`] | 56 B | peak memory of a registration per input point, before ICP's copy (measured in wasm, see below) |
//! | [`ICP_BYTES_PER_POINT`] | 72 B | peak memory per point of the (voxelised) cloud ICP works on: its copy, k-d tree and normals |
//! | [`MAX_POINTS_PER_CLOUD`] | 16,000,000 | points per cloud given to a registration: `MAX_CALL_BYTES / (2 x INPUT_BYTES_PER_POINT)` (19.2M), rounded down |
//! | ICP's cloud ([`check_icp_points`]) | `input x 56 B + icp x 72 B <= 1 GiB` per cloud | points each cloud keeps for ICP after voxelisation: 8,388,608 when nothing is thinned (`voxelSize: 0`), fewer the more input points there are |
//! | the hints' neighbourhoods ([`crate::spatial::neighbourhood`]) | at most 262,144 points x 84 B (21 MiB) per index | kept only by ICP clouds of at most [`crate::spatial::neighbourhood::MAX_POINTS`] points, so they fit beside the input at its limit (16M x 56 B + 262,144 x (72 + 84) B < 1 GiB) and need no budget of their own |
//! | [`ICP_COPIES_BYTES_PER_POINT`] | 117 B | the coarser copies of ICP's target ([`crate::icp::IcpTarget::with_levels`]) per point of the target: at most 3/4 of its points again, each with 72 B and the hints' 84 B; built only where they fit beside the input and the target ([`icp_copies_fit`]), else ICP searches the target alone |
//! | [`MAX_FILE_POINTS`] | 16,000,000 | points (vertices) a file may hold for the readers (the same figure: a cloud that cannot be registered is not worth decoding) |
//! | [`MAX_DECODED_BYTES`] | 1 GiB | bytes a compressed body (PCD `binary_compressed`) may decompress to |
//! | [`MAX_MODEL_DIM`] | 4,096 | every size in a model config (N, C, heads, hidden widths, H, J) |
//! | [`MAX_MODEL_LIST`] | 16 | entries of a config's hidden-width lists (`pos_hidden`, `head_hidden`) |
//! | [`MAX_MODEL_LAYERS`] | 16 | ARPS layers L |
//! | [`MAX_MODEL_PARAMETERS`] | 33,554,432 | parameters of a model (128 MiB as f32; the paper-size model has 13.8M) |
//! | [`MAX_MODEL_CONFIG_BYTES`] | 65,536 | bytes of a weights file's `config` JSON |
//!
//! **Where the bytes per point come from.** Measured as the growth of the WebAssembly memory of one
//! `register()` in Node (the package's Node build, default model) on two synthetic surface clouds of
//! N points each (`BENCHMARK.md`, "Memory"): with the default voxelisation (which keeps a small
//! fraction of the points for ICP) it grows by 49 bytes per input point from 1M to 4M points per
//! cloud; with `voxelSize: 0` (ICP on every point) by 114, so ICP's copy, k-d tree and normals take
//! about 65 bytes per point they keep. Per input point a registration holds the binding's copy of
//! the caller's array (12 B), the validated copy (12 B), the turned copy when an initial rotation is
//! given (12 B), the normalised copy (12 B) and the voxel grid's table while it runs (at most 16 B),
//! not all at once. The budgets round the measured figures up (56 and 72 bytes) for the
//! allocator's slack.
//!
//! Between calls a registrar keeps its last target (`pipeline::target`: the normalised copy, 12 B
//! per input point, and ICP's copy with its k-d tree and the normals found so far), which a
//! registration onto the same target reuses instead of allocating them again; a registration onto
//! another target drops it before allocating anything, so a call's peak stays within the budgets
//! above.
//!
//! A cloud over the limit should be downsampled before it is registered, e.g. on a voxel grid
//! ([`crate::sampling::voxel_downsample`]); the `voxelSize` option thins only the clouds ICP
//! uses, after the inputs are loaded, so it does not lift the input limit (a larger one lowers
//! what ICP keeps).

use crate::{Error, Result};

/// Memory one call may use, in bytes: half of wasm32's 4 GiB.
pub const MAX_CALL_BYTES: u64 = 2 << 30;

/// Peak memory of a registration per input point, before ICP's copy, in bytes (see the module
/// docs).
pub const INPUT_BYTES_PER_POINT: u64 = 56;

/// Peak memory per point of the cloud ICP works on (the voxelised copy, its k-d tree and
/// normals), in bytes (see the module docs).
pub const ICP_BYTES_PER_POINT: u64 = 72;

/// Most points per cloud a registration accepts: `MAX_CALL_BYTES / (2 * INPUT_BYTES_PER_POINT)`
/// (19,173,961), rounded down to 16,000,000 (what ICP keeps of them is bounded separately,
/// [`check_icp_points`]).
pub const MAX_POINTS_PER_CLOUD: usize = 16_000_000;

/// Most points (vertices) the readers decode from one file.
pub const MAX_FILE_POINTS: usize = MAX_POINTS_PER_CLOUD;

/// Most bytes a compressed body may decompress to.
pub const MAX_DECODED_BYTES: u64 = 1 << 30;

/// Bytes a file read whole from disk may hold ([`crate::io::read_file`], native only): 4 GiB,
/// more than any file of [`MAX_FILE_POINTS`] points needs, so that a device or pipe that never
/// ends (`/dev/zero`) is an error, not memory exhausted. (In JS the package refuses files over
/// 1 GiB before they reach the engine.)
pub const MAX_READ_BYTES: u64 = 4 << 30;

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
const _: () = assert!(2 * MAX_POINTS_PER_CLOUD as u64 * INPUT_BYTES_PER_POINT <= MAX_CALL_BYTES);

/// Fails with [`Error::TooLarge`] when a cloud given to a registration has more than
/// [`MAX_POINTS_PER_CLOUD`] points; `what` names it (`"source"`, `"target"`).
pub fn check_cloud_points(what: &str, n: usize) -> Result<()> {
    if n <= MAX_POINTS_PER_CLOUD {
        return Ok(());
    }
    Err(Error::TooLarge(format!(
        "{what} has {n} points, more than the {MAX_POINTS_PER_CLOUD} a registration accepts per cloud \
         (about {INPUT_BYTES_PER_POINT} bytes per point, within {} MiB per call, for WebAssembly's 4 GiB memory): \
         downsample it first, e.g. on a voxel grid (a voxel about {:.2}x the mean point spacing keeps about \
         {MAX_POINTS_PER_CLOUD} points); the voxelSize option thins only ICP's copy and does not lift this limit",
        MAX_CALL_BYTES >> 20,
        voxel_factor(n),
    )))
}

/// Most points a cloud of `input` points may keep for ICP: what fits its half of
/// [`MAX_CALL_BYTES`] next to the input ([`INPUT_BYTES_PER_POINT`] each), at
/// [`ICP_BYTES_PER_POINT`] each.
pub fn max_icp_points(input: usize) -> usize {
    let left = (MAX_CALL_BYTES / 2).saturating_sub((input as u64).saturating_mul(INPUT_BYTES_PER_POINT));
    (left / ICP_BYTES_PER_POINT) as usize
}

/// Most memory the coarser copies of ICP's target take per point of the target, in bytes: they
/// hold at most 3/4 of its points again ([`crate::icp::IcpTarget::with_levels`]), each with
/// [`ICP_BYTES_PER_POINT`] and the hints' neighbourhood
/// ([`crate::spatial::neighbourhood::BYTES_PER_POINT`]).
pub const ICP_COPIES_BYTES_PER_POINT: u64 =
    (ICP_BYTES_PER_POINT + crate::spatial::neighbourhood::BYTES_PER_POINT as u64) * 3 / 4;

/// Whether the coarser copies of ICP's target ([`crate::icp::IcpTarget::with_levels`]) of `icp`
/// points fit beside it and its `input` points in the cloud's half of [`MAX_CALL_BYTES`]
/// ([`ICP_COPIES_BYTES_PER_POINT`] each); without them ICP searches the target alone.
pub fn icp_copies_fit(input: usize, icp: usize) -> bool {
    let (input, icp) = (input as u64, icp as u64);
    let bytes = input
        .saturating_mul(INPUT_BYTES_PER_POINT)
        .saturating_add(icp.saturating_mul(ICP_BYTES_PER_POINT + ICP_COPIES_BYTES_PER_POINT));
    bytes <= MAX_CALL_BYTES / 2
}

/// Fails with [`Error::TooLarge`] when a cloud of `input` points keeps `icp` points for ICP after
/// voxelisation (`voxel`, in the caller's units; 0 for none) and the two do not fit its half of
/// the call's budget ([`max_icp_points`]); `what` names it. Checked before ICP builds anything
/// on those points.
pub fn check_icp_points(what: &str, input: usize, icp: usize, voxel: f64, default: bool) -> Result<()> {
    let max = max_icp_points(input);
    if icp <= max {
        return Ok(());
    }
    let (how, fix) = if voxel > 0.0 {
        // a surface keeps points as the square of the voxel shrinks: a size this much larger fits
        let fits = voxel * (icp as f64 / max.max(1) as f64).sqrt() * 1.1;
        let default = if default { " (the default: the cloud may fill a volume rather than a surface)" } else { "" };
        (format!("voxelSize {voxel}{default}"), format!("set voxelSize to {} or more", three_digits(fits)))
    } else {
        let how = "voxelSize 0 (every point; a size below a millionth of the clouds' half-extent counts as 0)";
        (how.to_string(), "set a larger voxelSize (or leave it unset for the default)".to_string())
    };
    Err(Error::TooLarge(format!(
        "{what} keeps {icp} of its {input} points for ICP at {how}, more than the {max} that fit next to them \
         (about {ICP_BYTES_PER_POINT} bytes per ICP point and {INPUT_BYTES_PER_POINT} per input point, within {} MiB \
         per cloud, half of the {} MiB a call may use in WebAssembly's 4 GiB memory): {fix}, or downsample the cloud first",
        MAX_CALL_BYTES >> 21,
        MAX_CALL_BYTES >> 20,
    )))
}

/// `v` (positive) with three significant digits, in fixed notation.
fn three_digits(v: f64) -> String {
    let decimals = (2.0 - v.log10().floor()).clamp(0.0, 20.0) as usize;
    format!("{v:.decimals$}")
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
        assert!(e.contains("20000000") && e.contains("16000000") && e.contains("voxel"), "{e}");
        assert!(check_file_points("PLY", MAX_FILE_POINTS as u64 + 1).is_err());
        assert!(check_file_points("PLY", 10).is_ok());
    }

    #[test]
    fn the_neighbourhoods_fit_beside_the_largest_input() {
        use crate::spatial::neighbourhood::{BYTES_PER_POINT, MAX_POINTS};
        let most = MAX_POINTS_PER_CLOUD as u64 * INPUT_BYTES_PER_POINT
            + MAX_POINTS as u64 * (ICP_BYTES_PER_POINT + BYTES_PER_POINT as u64);
        assert!(most <= MAX_CALL_BYTES / 2, "{most}");
    }

    #[test]
    fn coarser_copies_of_the_target_only_where_they_fit() {
        assert_eq!(ICP_COPIES_BYTES_PER_POINT, 117);
        // a 1M-point scan and ICP's 275k points of it, or the largest input at the default voxel
        assert!(icp_copies_fit(1_000_000, 275_000));
        assert!(icp_copies_fit(MAX_POINTS_PER_CLOUD, 200_000));
        // the largest input with as many ICP points as fit beside it: no room for copies
        assert!(!icp_copies_fit(MAX_POINTS_PER_CLOUD, max_icp_points(MAX_POINTS_PER_CLOUD)));
        assert!(!icp_copies_fit(0, 8_388_608));
        assert!(icp_copies_fit(0, 4_000_000));
    }

    #[test]
    fn icp_points_share_the_budget_with_the_input() {
        // nothing thinned: the old full-cloud limit (128 bytes a point) still fits
        assert!(check_icp_points("source", 8_000_000, 8_000_000, 0.0, false).is_ok());
        assert_eq!(max_icp_points(0), (1 << 30) / ICP_BYTES_PER_POINT as usize);
        // the most input points leave room for a few million ICP points, not for all of them
        let max = max_icp_points(MAX_POINTS_PER_CLOUD);
        assert!(max > 1_000_000 && max < MAX_POINTS_PER_CLOUD, "{max}");
        assert!(check_icp_points("target", MAX_POINTS_PER_CLOUD, max, 0.001, false).is_ok());
        let e =
            check_icp_points("target", MAX_POINTS_PER_CLOUD, MAX_POINTS_PER_CLOUD, 0.0, false).unwrap_err().to_string();
        assert!(
            e.contains("target keeps 16000000 of its 16000000")
                && e.contains("voxelSize 0")
                && e.contains(&max.to_string()),
            "{e}"
        );
        let e = check_icp_points("source", 12_000_000, 9_000_000, 0.25, false).unwrap_err().to_string();
        let fits = 0.25 * (9_000_000.0 / max_icp_points(12_000_000) as f64).sqrt() * 1.1;
        assert!(
            e.contains("at voxelSize 0.25, more than")
                && e.contains(&format!("set voxelSize to {} or more", three_digits(fits))),
            "{e}"
        );
        // the default voxel size is named as such, with what makes it keep too many
        let e = check_icp_points("source", 12_000_000, 9_000_000, 0.25, true).unwrap_err().to_string();
        assert!(e.contains("voxelSize 0.25 (the default: the cloud may fill a volume"), "{e}");
        assert_eq!(
            (three_digits(0.0123456), three_digits(2.5), three_digits(1234.6)),
            ("0.0123".into(), "2.50".into(), "1235".into())
        );
        // an input past every budget leaves room for none
        assert_eq!(max_icp_points(usize::MAX / 64), 0);
    }
}
