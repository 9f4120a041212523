//! A LAS file moved as it is: every point record's X, Y, Z mapped by a rigid (or uniformly
//! scaled) transform in f64 and stored again with the file's own scales (times the transform's
//! scale: a change of unit keeps the points' precision, 0.01 mm staying 0.01 mm in metres) and,
//! where the moved points still fit them, its own offsets (else new ones near the moved points'
//! centre, round where the integers still fit); the header's scales, offsets and bounds updated;
//! every other byte kept
//! (intensity, returns, classification, GPS time, colour, extra bytes, the VLRs and EVLRs, the
//! CRS records). What saves a registered survey in the target's frame as the LAS its
//! tools read. A LAZ file comes back as LAZ: the LAS file it compresses, moved, compressed again
//! (`laz_write`).

use super::las::{decompressed, err, Header, BOUNDS_AT, OFFSETS_AT, SCALES_AT};
use super::laz_write::compressed;
use super::motion::Motion;
use crate::Result;
use nalgebra::Matrix4;

/// The LAS file `bytes` with its points moved by `m` (`T_target_source`: rigid, or rigid times a
/// uniform scale), everything else as it was (see the module docs); a LAZ file comes back as LAZ.
/// Errors: a file the LAS reader refuses, points the file's scales cannot store once moved (more
/// than 2^31 steps from the new offset), a transform that is not rigid (or uniformly scaled), a
/// LAZ file whose points decompress to more than [`crate::limits::MAX_DECODED_BYTES`].
pub fn transform_las(bytes: &[u8], m: &Matrix4<f64>) -> Result<Vec<u8>> {
    let motion = Motion::new(m)?;
    let h = Header::read(bytes)?;
    if h.compressed {
        let las = decompressed(bytes, &h)?;
        let h_las = Header::read(&las)?;
        let moved = move_records(las, &h_las, &motion)?;
        return compressed(bytes, &h, &moved);
    }
    h.records(bytes)?;
    move_records(bytes.to_vec(), &h, &motion)
}

/// The offset of an axis whose moved points span `lo` to `hi`: their centre rounded to the
/// coarsest power of ten (1e7 down to 1) that leaves every point within 2e9 steps of `scale`
/// of it (`i32` holds 2^31) (a survey's offsets as tools write them: 400000, 5600000, 0), else the centre on the
/// scale's grid.
fn round_offset(lo: f64, hi: f64, scale: f64) -> f64 {
    let centre = (lo + hi) / 2.0;
    let fits = |offset: f64| fits(lo, hi, offset, scale);
    (0..=7)
        .rev()
        .map(|k| 10f64.powi(k))
        .filter(|&step| step >= scale)
        .map(|step| (centre / step).round() * step)
        .find(|&offset| fits(offset))
        .unwrap_or_else(|| (centre / scale).round() * scale)
}

/// Whether points from `lo` to `hi` on an axis lie within 2e9 steps of `scale` of `offset` (`i32`
/// holds 2^31).
fn fits(lo: f64, hi: f64, offset: f64, scale: f64) -> bool {
    [lo, hi].iter().all(|v| ((v - offset) / scale).abs() < 2_000_000_000.0)
}

/// A LAS scale times the motion's uniform `factor`, to 12 significant digits (0.01 times 0.001
/// is 1e-5, not 1.0000000000000001e-5); the scale itself for a factor of 1.
fn scaled(scale: f64, factor: f64) -> f64 {
    if factor == 1.0 {
        return scale;
    }
    let v = scale * factor;
    format!("{v:.11e}").parse().unwrap_or(v)
}

/// `out`, an uncompressed LAS file described by `h`, with its records moved and its header's
/// scales, offsets and bounds updated.
fn move_records(mut out: Vec<u8>, h: &Header, motion: &Motion) -> Result<Vec<u8>> {
    let records = h.records(&out)?;
    let end = h.offset + records.len();
    let n = h.count as usize;
    let moved = |record: &[u8]| motion.point(h.point(record));
    // the points' grid, scaled with them (a change of unit)
    let scale = h.scale.map(|s| scaled(s, motion.scale().abs()));
    // the offsets: the file's own where the moved points fit them (a correction of a few metres
    // keeps a survey's header as its tools wrote it), else near the moved points' centre, round
    // where the integers fit
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for record in records.chunks_exact(h.record_len) {
        let q = moved(record);
        for k in 0..3 {
            lo[k] = lo[k].min(q[k]);
            hi[k] = hi[k].max(q[k]);
        }
    }
    let shift: [f64; 3] = if n == 0 {
        h.shift
    } else {
        std::array::from_fn(|k| match fits(lo[k], hi[k], h.shift[k], scale[k]) {
            true => h.shift[k],
            false => round_offset(lo[k], hi[k], scale[k]),
        })
    };
    for (k, axis) in ["x", "y", "z"].into_iter().enumerate().filter(|_| n > 0) {
        let steps = [lo[k], hi[k]].map(|v| ((v - shift[k]) / scale[k]).round());
        if steps.iter().any(|s| !(*s >= i32::MIN as f64 && *s <= i32::MAX as f64)) {
            return Err(err(format!(
                "the moved points span {} to {} in {axis}, more than the file's scale {} can store in 32-bit integers",
                lo[k], hi[k], scale[k]
            )));
        }
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for record in out[h.offset..end].chunks_exact_mut(h.record_len) {
        let q = moved(record);
        for k in 0..3 {
            let stored = ((q[k] - shift[k]) / scale[k]).round() as i32;
            record[4 * k..4 * k + 4].copy_from_slice(&stored.to_le_bytes());
            let v = stored as f64 * scale[k] + shift[k];
            lo[k] = lo[k].min(v);
            hi[k] = hi[k].max(v);
        }
    }
    for k in 0..3 {
        out[SCALES_AT + 8 * k..SCALES_AT + 8 * k + 8].copy_from_slice(&scale[k].to_le_bytes());
        out[OFFSETS_AT + 8 * k..OFFSETS_AT + 8 * k + 8].copy_from_slice(&shift[k].to_le_bytes());
        if n > 0 {
            let at = BOUNDS_AT + 16 * k;
            out[at..at + 8].copy_from_slice(&hi[k].to_le_bytes());
            out[at + 8..at + 16].copy_from_slice(&lo[k].to_le_bytes());
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::round_offset;

    #[test]
    fn offsets_are_round_where_the_integers_fit() {
        // a survey on a map grid at millimetres: within 2e9 mm (2,000 km) of a power of ten
        assert_eq!(round_offset(400_120.5, 400_380.25, 0.001), 0.0);
        assert_eq!(round_offset(5_600_100.5, 5_600_300.0, 0.001), 6_000_000.0);
        // at 1e-6 steps the points must stay within 2,000 units: 400,000 holds 400,120-400,380
        assert_eq!(round_offset(400_120.5, 400_380.25, 1e-6), 400_000.0);
        // a span of 3,000 units at 1e-6 needs the centre itself, on the scale's grid
        let o = round_offset(400_000.5, 403_999.5, 1e-6);
        assert!((o - 402_000.0).abs() < 1e-6, "{o}");
        assert_eq!(round_offset(-12.5, 3.0, 0.01), 0.0);
    }
}
