//! A LAS file compressed again as the LAZ file it came from: what saves a moved LAZ survey as
//! LAZ. The points are compressed by the `laz` crate (the Rust port of LASzip) with the items
//! LASzip writes today for the point format (point-wise chunks for formats 0 to 5, layered ones
//! for 6 to 10), in chunks of the original file's size (LASzip's 50,000 points when it had none
//! of a fixed size); the LAZ file's header and VLRs are kept, its LASzip record rewritten for
//! those items. A COPC file (LAZ whose chunks form an octree of the points' space, indexed by
//! byte offsets) comes back as a plain LAZ file: its `copc` VLR and EVLR are left out, since the
//! moved points neither lie in that octree nor at those offsets.

use super::las::{append_tail, err, laszip_among, vlrs, Header, BOUNDS_AT, MIN_RECORD, SCALES_AT, VLR_HEADER};
use crate::Result;
use laz::laszip::{LasZipCompressor, LazItemRecordBuilder, LazVlr, LazVlrBuilder};
use std::io::Cursor;

/// The chunk size LASzip writes by default.
const DEFAULT_CHUNK: u32 = 50_000;
/// LASzip's compressor types (the VLR's first field) that write chunks of a fixed size.
const CHUNKED: [u16; 2] = [2, 3];
/// The user id of COPC's records.
const COPC_USER: &[u8] = b"copc";
/// Where the LAS 1.4 header holds the start of the first extended VLR (u64) and their number
/// (u32), and the bytes of an extended VLR's header.
const EVLRS_AT: usize = 235;
const EVLR_COUNT_AT: usize = 243;
const EVLR_HEADER: usize = 60;

/// The LAZ file `laz` (described by `h_laz`) with the point records, the point data's offsets and
/// bounds, and what follows the points taken from `las`, the uncompressed LAS file that its
/// points decompress to (`las::decompressed`), changed: its points moved, say.
pub(super) fn compressed(laz: &[u8], h_laz: &Header, las: &[u8]) -> Result<Vec<u8>> {
    let h = Header::read(las)?;
    let records = h.records(las)?;
    let laz_err = |e: laz::LasZipError| err(format!("the points cannot be compressed: {e}"));
    let io_err = |e: std::io::Error| err(format!("the points cannot be compressed: {e}"));
    let all = vlrs(laz, h_laz)?;
    let (vlr_data, vlr_range) = laszip_among(laz, &all)?;
    let original = LazVlr::from_buffer(vlr_data).map_err(laz_err)?;
    let fixed = CHUNKED.contains(&u16::from_le_bytes([vlr_data[0], vlr_data[1]]))
        && !original.uses_variable_size_chunks()
        && original.chunk_size() > 0;
    let chunk = if fixed { original.chunk_size() } else { DEFAULT_CHUNK };
    let format = las[104] & 0x3F;
    let extra = u16::try_from(h.record_len - MIN_RECORD[format as usize])
        .map_err(|_| err(format!("point records of {} bytes are too long to compress", h.record_len)))?;
    let items = LazItemRecordBuilder::default_for_point_format_id(format, extra).map_err(laz_err)?;
    let vlr = LazVlrBuilder::new(items).with_fixed_chunk_size(chunk).build();
    let mut payload = Vec::new();
    vlr.write_to(&mut payload).map_err(io_err)?;
    let payload_len = u16::try_from(payload.len()).map_err(|_| err("the LASzip record is too long"))?;

    // the LAZ file's header and VLRs, its LASzip record's data replaced, COPC's left out (and
    // what lies between the last of them and the points kept)
    let copc = all.iter().any(|v| v.user == COPC_USER);
    let vlrs_end = all.last().map_or(h_laz.vlrs_at, |v| v.range.end);
    let mut out = Vec::with_capacity(h_laz.offset + payload.len() + records.len() / 4);
    out.extend_from_slice(&laz[..h_laz.vlrs_at]);
    let kept = all.iter().filter(|v| v.user != COPC_USER).count() as u32;
    out[100..104].copy_from_slice(&kept.to_le_bytes());
    for v in all.iter().filter(|v| v.user != COPC_USER) {
        if v.range == vlr_range {
            let at = out.len();
            out.extend_from_slice(&laz[v.range.start..v.range.start + VLR_HEADER]);
            out[at + 20..at + 22].copy_from_slice(&payload_len.to_le_bytes());
            out.extend_from_slice(&payload);
        } else {
            out.extend_from_slice(&laz[v.range.clone()]);
        }
    }
    out.extend_from_slice(&laz[vlrs_end..h_laz.offset]);
    // the changed points' scales, offsets and bounds (contiguous), and where they now start
    out[SCALES_AT..BOUNDS_AT + 48].copy_from_slice(&las[SCALES_AT..BOUNDS_AT + 48]);
    let offset = u32::try_from(out.len()).map_err(|_| err("the VLRs are too long"))?;
    out[96..100].copy_from_slice(&offset.to_le_bytes());

    // the points, compressed after them (the chunk table's offset is the file's)
    let mut cursor = Cursor::new(out);
    cursor.set_position(offset as u64);
    let mut compressor = LasZipCompressor::new(cursor, vlr).map_err(laz_err)?;
    compressor.compress_many(records).map_err(io_err)?;
    compressor.done().map_err(io_err)?;
    let mut out = compressor.into_inner().into_inner();
    if copc {
        append_evlrs_but_copc(las, &mut out)?;
    } else {
        append_tail(las, &h, &mut out);
    }
    Ok(out)
}

/// Appends to `out` the extended VLRs of the LAS 1.4 file `las` but COPC's, their start and
/// number in `out`'s header set to theirs; an error when one runs past the file's end.
fn append_evlrs_but_copc(las: &[u8], out: &mut Vec<u8>) -> Result<()> {
    // a header without extended VLRs (before LAS 1.4)
    if (u16::from_le_bytes([las[94], las[95]]) as usize) < EVLR_COUNT_AT + 4 {
        return Ok(());
    }
    let start = u64::from_le_bytes(las[EVLRS_AT..EVLRS_AT + 8].try_into().expect("8 bytes"));
    let count = u32::from_le_bytes(las[EVLR_COUNT_AT..EVLR_COUNT_AT + 4].try_into().expect("4 bytes"));
    let count = if start > 0 { count } else { 0 };
    let (first, mut kept) = (out.len() as u64, 0u32);
    let mut at = usize::try_from(start).unwrap_or(usize::MAX);
    for k in 0..count {
        let past = || err(format!("extended VLR {} of {count} runs past the file's end", k + 1));
        let header = at.checked_add(EVLR_HEADER).filter(|&end| end <= las.len()).ok_or_else(past)?;
        let len = u64::from_le_bytes(las[at + 20..at + 28].try_into().expect("8 bytes"));
        let end = usize::try_from(len).ok().and_then(|len| header.checked_add(len)).filter(|&end| end <= las.len());
        let end = end.ok_or_else(past)?;
        let user = las[at + 2..at + 18].split(|&b| b == 0).next().unwrap_or_default();
        if user != COPC_USER {
            out.extend_from_slice(&las[at..end]);
            kept += 1;
        }
        at = end;
    }
    out[EVLRS_AT..EVLRS_AT + 8].copy_from_slice(&(if kept > 0 { first } else { 0 }).to_le_bytes());
    out[EVLR_COUNT_AT..EVLR_COUNT_AT + 4].copy_from_slice(&kept.to_le_bytes());
    Ok(())
}
