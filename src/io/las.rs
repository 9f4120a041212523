//! LAS (the ASPRS LiDAR exchange format, versions 1.0 to 1.4, point formats 0 to 10) and LAZ
//! (LAS compressed by LASzip): the X, Y, Z of every point record, as `X * scale + offset` in
//! `f64`, so georeferenced coordinates keep every digit the file holds. Every record is read,
//! whatever its classification (noise classes and withheld points too, as PDAL and laspy read
//! them), unless the caller names the classes to keep ([`super::ReadOptions::classes`]);
//! isolated noise far from the rest is what the registration's far-outlier step leaves out
//! (`Options::outliers`).
//!
//! The header is read here; a LAZ file's points are decompressed by the `laz` crate (the Rust
//! port of LASzip), only their X, Y, Z layers where the file is layered (point formats 6 to 10).
//! That crate trusts the file's chunk table and layer sizes, so they are checked here first: a
//! count that the bytes could not hold is an error, not an allocation or a panic.

use super::classes::Classes;
use super::util::{bounded_capacity, u32_at};
use crate::{Error, Result};
use laz::laszip::{ChunkTable, LasZipDecompressor, LazItemType, LazVlr};
use laz::DecompressionSelection;
use std::io::Cursor;

pub(super) const FORMAT: &str = "LAS";

/// Bytes of the public header block of LAS 1.0 to 1.2 (1.3 adds 8, 1.4 adds 148).
const HEADER_1_0: usize = 227;
/// Bytes of the public header block of LAS 1.4, which holds the 64-bit point count.
const HEADER_1_4: usize = 375;
/// Bytes of a variable length record's header.
pub(super) const VLR_HEADER: usize = 54;
/// The LASzip VLR's user id and record id.
const LASZIP_USER: &[u8] = b"laszip encoded";
const LASZIP_RECORD: u16 = 22204;
/// LASzip's compressor types (the VLR's first field).
const POINTWISE: u16 = 1;
const LAYERED: u16 = 3;
/// Layers of a LAS 1.4 point record (`Point14`) in a layered chunk: channel / returns / XY, Z,
/// classification, flags, intensity, scan angle, user data, point source, GPS time.
const POINT14_LAYERS: usize = 9;

/// Where the public header block holds the x, y, z scales and offsets (f64 each), and max x,
/// min x, max y, min y, max z, min z (f64 each).
pub(super) const SCALES_AT: usize = 131;
pub(super) const OFFSETS_AT: usize = 155;
pub(super) const BOUNDS_AT: usize = 179;

/// The shortest point record of each point format 0 to 10 (the file may add extra bytes).
pub(super) const MIN_RECORD: [usize; 11] = [20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67];

pub(super) fn err(message: impl Into<String>) -> Error {
    Error::parse(FORMAT, message)
}

fn u16_at(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([b[at], b[at + 1]])
}

fn u64_at(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(b[at..at + 8].try_into().expect("8 bytes"))
}

fn f64_at(b: &[u8], at: usize) -> f64 {
    f64::from_le_bytes(b[at..at + 8].try_into().expect("8 bytes"))
}

/// What the public header block says about the points.
pub(super) struct Header {
    /// Where the point records start.
    pub(super) offset: usize,
    /// Where the variable length records start (the header's size).
    pub(super) vlrs_at: usize,
    vlr_count: u32,
    pub(super) compressed: bool,
    /// The point data format, 0 to 10.
    format: u8,
    pub(super) record_len: usize,
    pub(super) count: u64,
    pub(super) scale: [f64; 3],
    pub(super) shift: [f64; 3],
}

impl Header {
    pub(super) fn read(bytes: &[u8]) -> Result<Header> {
        if !bytes.starts_with(b"LASF") {
            return Err(err("the file does not start with the 'LASF' signature"));
        }
        if bytes.len() < HEADER_1_0 {
            return Err(err(format!("the file has {} bytes, fewer than a LAS header's {HEADER_1_0}", bytes.len())));
        }
        let (major, minor) = (bytes[24], bytes[25]);
        if major != 1 || minor > 4 {
            return Err(err(format!("version {major}.{minor} is not supported (LAS 1.0 to 1.4 are)")));
        }
        let header_size = u16_at(bytes, 94) as usize;
        let offset = u32_at(bytes, 96) as usize;
        if header_size < HEADER_1_0 || header_size > bytes.len() {
            return Err(err(format!(
                "the header size {header_size} is not between {HEADER_1_0} and the file's {} bytes",
                bytes.len()
            )));
        }
        if offset < header_size || offset > bytes.len() {
            return Err(err(format!(
                "the offset to the point data {offset} is not between the header's {header_size} bytes and the file's {}",
                bytes.len()
            )));
        }
        let id = bytes[104];
        // LASzip marks a compressed format by setting bit 7 (older writers bit 6)
        let (compressed, format) = (id & 0xC0 != 0, id & 0x3F);
        let Some(&min_record) = MIN_RECORD.get(format as usize) else {
            return Err(err(format!("point data format {format} is not one of 0 to 10")));
        };
        let record_len = u16_at(bytes, 105) as usize;
        if record_len < min_record {
            return Err(err(format!(
                "point records of {record_len} bytes are shorter than point data format {format}'s {min_record}"
            )));
        }
        let legacy = u32_at(bytes, 107) as u64;
        let count = if minor >= 4 && header_size >= HEADER_1_4 {
            Some(u64_at(bytes, 247)).filter(|&n| n > 0).unwrap_or(legacy)
        } else {
            legacy
        };
        let (scale, shift) =
            ([0, 1, 2].map(|k| f64_at(bytes, SCALES_AT + 8 * k)), [0, 1, 2].map(|k| f64_at(bytes, OFFSETS_AT + 8 * k)));
        for (axis, (s, o)) in ["x", "y", "z"].iter().zip(scale.iter().zip(&shift)) {
            if !s.is_finite() || *s == 0.0 || !o.is_finite() {
                return Err(err(format!(
                    "the {axis} scale {s} and offset {o} do not map the stored integers to coordinates \
                     (the scale must be finite and non-zero, the offset finite)"
                )));
            }
        }
        Ok(Header {
            offset,
            vlrs_at: header_size,
            vlr_count: u32_at(bytes, 100),
            compressed,
            format,
            record_len,
            count,
            scale,
            shift,
        })
    }

    /// The bytes of the `count` point records of an uncompressed file; an error when the file
    /// holds fewer.
    pub(super) fn records<'a>(&self, bytes: &'a [u8]) -> Result<&'a [u8]> {
        let held = (bytes.len() - self.offset) / self.record_len;
        if (held as u64) < self.count {
            return Err(err(format!(
                "the header claims {} points of {} bytes from byte {}, but the file holds {held}",
                self.count, self.record_len, self.offset
            )));
        }
        Ok(&bytes[self.offset..self.offset + self.count as usize * self.record_len])
    }

    /// The point of a record's first 12 bytes (X, Y, Z as `i32`, in every point format).
    pub(super) fn point(&self, record: &[u8]) -> [f64; 3] {
        [0, 1, 2].map(|k| u32_at(record, 4 * k) as i32 as f64 * self.scale[k] + self.shift[k])
    }

    /// A record's classification code: the low 5 bits of byte 15 in point formats 0 to 5 (the
    /// others are flags), byte 16 in formats 6 to 10.
    fn class(&self, record: &[u8]) -> u8 {
        if self.format < 6 {
            record[15] & 0x1F
        } else {
            record[16]
        }
    }
}

/// Reads the points of a LAS or LAZ file: every record, or with `classes` those of these
/// classification codes (an error when none is, naming the classes the file holds).
pub(crate) fn read(bytes: &[u8], classes: Option<Classes>) -> Result<Vec<[f64; 3]>> {
    let header = Header::read(bytes)?;
    crate::limits::check_file_points(FORMAT, header.count)?;
    let mut held = [0u64; 256];
    let mut keep = |record: &[u8]| {
        classes.is_none_or(|c| {
            let class = header.class(record);
            held[usize::from(class)] += 1;
            c.has(class)
        })
    };
    let points = if header.compressed {
        read_compressed(bytes, &header, classes.is_some(), &mut keep)
    } else {
        read_records(bytes, &header, &mut keep)
    }?;
    match classes {
        Some(c) if points.is_empty() && header.count > 0 => {
            let found: Vec<String> = (0..=255u8)
                .filter(|k| held[usize::from(*k)] > 0)
                .map(|k| format!("{k} ({})", held[usize::from(k)]))
                .collect();
            Err(err(format!(
                "none of its {} points is of classes {} (it holds classes {}, points in brackets)",
                header.count,
                c.list(),
                found.join(", ")
            )))
        }
        _ => Ok(points),
    }
}

/// The points of an uncompressed file whose records `keep` keeps.
fn read_records(bytes: &[u8], h: &Header, keep: &mut dyn FnMut(&[u8]) -> bool) -> Result<Vec<[f64; 3]>> {
    Ok(h.records(bytes)?.chunks_exact(h.record_len).filter(|r| keep(r)).map(|r| h.point(r)).collect())
}

/// A variable length record after the public header block.
pub(super) struct Vlr<'a> {
    /// Its user id, up to the first NUL.
    pub(super) user: &'a [u8],
    pub(super) record: u16,
    /// Where the whole record (its header and data) lies in the file.
    pub(super) range: std::ops::Range<usize>,
}

/// The variable length records between the header and the point data; an error when one runs
/// past the start of the point data.
pub(super) fn vlrs<'a>(bytes: &'a [u8], h: &Header) -> Result<Vec<Vlr<'a>>> {
    let mut at = h.vlrs_at;
    let mut out = Vec::new();
    for k in 0..h.vlr_count {
        let past = |what: String| {
            err(format!(
                "variable length record {} of {}{what} runs past the start of the point data (byte {})",
                k + 1,
                h.vlr_count,
                h.offset
            ))
        };
        if at + VLR_HEADER > h.offset {
            return Err(past(String::new()));
        }
        let user = &bytes[at + 2..at + 18];
        let record = u16_at(bytes, at + 18);
        let len = u16_at(bytes, at + 20) as usize;
        let data = at + VLR_HEADER;
        if data + len > h.offset {
            return Err(past(format!(" ({len} bytes from byte {data})")));
        }
        let user = user.split(|&b| b == 0).next().unwrap_or_default();
        out.push(Vlr { user, record, range: at..data + len });
        at = data + len;
    }
    Ok(out)
}

/// The LASzip VLR's data, among the variable length records after the header, and where the
/// whole record (its header and data) lies in the file.
pub(super) fn laszip_vlr<'a>(bytes: &'a [u8], h: &Header) -> Result<(&'a [u8], std::ops::Range<usize>)> {
    laszip_among(bytes, &vlrs(bytes, h)?)
}

/// [`laszip_vlr`] among the file's records `all` ([`vlrs`]).
pub(super) fn laszip_among<'a>(bytes: &'a [u8], all: &[Vlr]) -> Result<(&'a [u8], std::ops::Range<usize>)> {
    all.iter()
        .find(|v| v.user == LASZIP_USER && v.record == LASZIP_RECORD)
        .map(|v| (&bytes[v.range.start + VLR_HEADER..v.range.end], v.range.clone()))
        .ok_or_else(|| err("the point data format is marked compressed (LAZ), but the file has no LASzip record"))
}

/// A LAZ file's decompressor at its first point, once the file's LASzip record, chunk table and
/// layer sizes are checked (the `laz` crate trusts them); `selection`: the layers to decode.
fn decompressor<'a>(
    bytes: &'a [u8],
    h: &Header,
    selection: DecompressionSelection,
) -> Result<LasZipDecompressor<'a, Cursor<&'a [u8]>>> {
    let (vlr_data, _) = laszip_vlr(bytes, h)?;
    let laz_err = |e: laz::LasZipError| err(format!("the LASzip record cannot be used: {e}"));
    let vlr = LazVlr::from_buffer(vlr_data).map_err(laz_err)?;
    let compressor = u16_at(vlr_data, 0);
    let first = vlr.items().first().map(|i| (i.item_type(), i.version()));
    let Some((LazItemType::Point10 | LazItemType::Point14, version)) = first else {
        return Err(err(format!("the LASzip record's first item is {first:?}, not a point (Point10 or Point14)")));
    };
    // the crate decodes layers by the items' version (3 and 4), whatever the compressor says; the
    // layer sizes are checked only for a layered compressor, so the two must agree
    let layered = version >= 3;
    if layered != (compressor == LAYERED) {
        return Err(err(format!(
            "the LASzip record's compressor ({compressor}) and its items' version ({version}) disagree on whether \
             the points are layered"
        )));
    }
    // each item as large as the crate decodes it (it slices the point by its own sizes), and
    // together the header's point record
    let mut bytes_per_point = 0u64;
    for item in vlr.items() {
        let decoded = match item.item_type() {
            LazItemType::Byte(n) | LazItemType::Byte14(n) => n,
            LazItemType::Point10 => 20,
            LazItemType::GpsTime => 8,
            LazItemType::RGB12 | LazItemType::RGB14 => 6,
            LazItemType::RGBNIR14 => 8,
            LazItemType::WavePacket13 | LazItemType::WavePacket14 => 29,
            LazItemType::Point14 => 30,
        };
        if item.size() != decoded {
            return Err(err(format!(
                "the LASzip record's {:?} item says {} bytes, not its {decoded}",
                item.item_type(),
                item.size()
            )));
        }
        bytes_per_point += u64::from(decoded);
    }
    if bytes_per_point != h.record_len as u64 {
        return Err(err(format!(
            "the LASzip record's items make {bytes_per_point}-byte points, the header {}-byte ones",
            h.record_len
        )));
    }
    if compressor != POINTWISE {
        check_chunks(bytes, h, &vlr, layered)?;
    } else if vlr.uses_variable_size_chunks() {
        // one stream without chunks cannot have chunks of variable size (the crate panics on it)
        return Err(err("the LASzip record has no chunks (point-wise) but says they vary in size"));
    }
    let mut cursor = Cursor::new(bytes);
    cursor.set_position(h.offset as u64);
    LasZipDecompressor::selective(cursor, vlr, selection).map_err(|e| {
        err(format!("the compressed points cannot be read (is the file cut short? it has {} bytes): {e}", bytes.len()))
    })
}

/// The points of a LAZ file, decompressed by the `laz` crate once its chunk table and layer
/// sizes are known to fit in the file.
fn read_compressed(
    bytes: &[u8],
    h: &Header,
    classes: bool,
    keep: &mut dyn FnMut(&[u8]) -> bool,
) -> Result<Vec<[f64; 3]>> {
    // only X, Y, Z (and what they are coded with) where the file is layered, and the
    // classification when the caller keeps some classes
    let class = if classes { DecompressionSelection::CLASSIFICATION } else { 0 };
    let selection =
        DecompressionSelection(DecompressionSelection::XY_RETURNS_CHANNEL | DecompressionSelection::Z | class);
    // reserved as if the points were stored uncompressed (fewer than a compressed file holds), the
    // rest grows as they decode
    let mut points = Vec::with_capacity(bounded_capacity(h.count, bytes.len() - h.offset, h.record_len));
    each_record(bytes, h, selection, &mut |record| {
        if keep(record) {
            points.push(h.point(record))
        }
    })?;
    Ok(points)
}

/// Calls `visit` with each of a LAZ file's `count` point records, decompressed (the layers
/// `selection` names; the others left as zeros).
fn each_record(
    bytes: &[u8],
    h: &Header,
    selection: DecompressionSelection,
    visit: &mut dyn FnMut(&[u8]),
) -> Result<()> {
    let mut decompressor = decompressor(bytes, h, selection)?;
    let mut record = vec![0u8; h.record_len];
    for n in 0..h.count {
        decompressor
            .decompress_one(&mut record)
            .map_err(|e| err(format!("the compressed points end or break after {n} of {} points: {e}", h.count)))?;
        visit(&record);
    }
    Ok(())
}

/// Where the LAS 1.3 header holds the start of the waveform data packet record, and the LAS 1.4
/// header the start of the first extended VLR (u64 each).
const WAVEFORM_AT: usize = 227;
const EVLRS_AT: usize = 235;

/// A LAZ file as the LAS file it compresses: the header with the point format's compression bit
/// cleared, its VLRs but the LASzip record, every point record decompressed whole, then the
/// extended VLRs (and waveform record) that followed the compressed points, their start in the
/// header moved to where they now are. An error when the records would decompress to more than
/// [`crate::limits::MAX_DECODED_BYTES`].
pub(super) fn decompressed(bytes: &[u8], h: &Header) -> Result<Vec<u8>> {
    let size = h.count.saturating_mul(h.record_len as u64);
    if size > crate::limits::MAX_DECODED_BYTES {
        return Err(Error::TooLarge(format!(
            "the LAZ file's {} points of {} bytes decompress to {size} bytes, more than the {} decoded at once \
             (WebAssembly has 4 GiB of memory): save its points instead",
            h.count,
            h.record_len,
            crate::limits::MAX_DECODED_BYTES
        )));
    }
    let (_, vlr) = laszip_vlr(bytes, h)?;
    // header and VLRs without the LASzip record (and what lies between them and the points)
    // reserved up to four times the file (a lying count cannot make us allocate), the rest grows
    let mut out = Vec::with_capacity(h.offset + (size as usize).min(4 * bytes.len()));
    out.extend_from_slice(&bytes[..vlr.start]);
    out.extend_from_slice(&bytes[vlr.end..h.offset]);
    let offset = out.len();
    out[96..100].copy_from_slice(&(offset as u32).to_le_bytes());
    out[100..104].copy_from_slice(&(h.vlr_count - 1).to_le_bytes());
    out[104] &= 0x3F;
    each_record(bytes, h, DecompressionSelection::all(), &mut |record| out.extend_from_slice(record))?;
    // what follows the compressed points and their chunk table
    append_tail(bytes, h, &mut out);
    Ok(out)
}

/// Appends to `out` (a LAS or LAZ file up to the end of its point data, its header copied from
/// `bytes`) what follows the point data in `bytes` (described by `h`): the waveform records and
/// extended VLRs the header points to, from the first of them on, their starts in `out`'s header
/// moved to where they now are.
pub(super) fn append_tail(bytes: &[u8], h: &Header, out: &mut Vec<u8>) {
    let pointers: Vec<usize> = [(3, WAVEFORM_AT), (4, EVLRS_AT)]
        .into_iter()
        .filter(|&(minor, at)| bytes[25] >= minor && h.vlrs_at >= at + 8)
        .map(|(_, at)| at)
        .collect();
    let starts =
        pointers.iter().map(|&at| u64_at(bytes, at)).filter(|&v| v > h.offset as u64 && v <= bytes.len() as u64);
    if let Some(first) = starts.min() {
        let (old, new) = (first as usize, out.len());
        out.extend_from_slice(&bytes[old..]);
        for at in pointers {
            let v = u64_at(bytes, at);
            if v >= first {
                out[at..at + 8].copy_from_slice(&(v - old as u64 + new as u64).to_le_bytes());
            }
        }
    }
}

/// Checks the chunk table of a chunked LAZ file before the `laz` crate reads it: its chunk count
/// against the bytes before it, its chunks' points against the header's count, and in a layered
/// file each chunk's layer sizes against the chunk's bytes (the crate allocates what they say).
fn check_chunks(bytes: &[u8], h: &Header, vlr: &LazVlr, layered: bool) -> Result<()> {
    let data = h.offset as u64 + 8;
    if bytes.len() < h.offset + 8 {
        return Err(err("the compressed point data ends before its chunk table's offset"));
    }
    // the table's offset, or -1 and the offset in the file's last 8 bytes (a writer that could
    // not seek back)
    let mut table = u64_at(bytes, h.offset) as i64;
    if table <= h.offset as i64 && bytes.len() >= h.offset + 16 {
        table = u64_at(bytes, bytes.len() - 8) as i64;
    }
    let len = bytes.len() as u64;
    if table <= h.offset as i64 || table as u64 + 8 > len {
        if layered || vlr.uses_variable_size_chunks() {
            return Err(err(format!(
                "the compressed point data has no chunk table (its offset {table} is not within the file's {len} bytes)"
            )));
        }
        return Ok(());
    }
    let table = table as u64;
    let chunks = u32_at(bytes, table as usize + 4) as u64;
    // every chunk starts with its first point uncompressed
    let room = table.saturating_sub(data) / h.record_len as u64;
    if chunks > room {
        return Err(err(format!(
            "the chunk table at byte {table} lists {chunks} chunks, more than the {room} that the compressed data before it could hold"
        )));
    }
    let mut cursor = Cursor::new(bytes);
    cursor.set_position(h.offset as u64);
    let entries =
        ChunkTable::read_from(&mut cursor, vlr).map_err(|e| err(format!("the chunk table cannot be read: {e}")))?;
    let entries = entries.as_ref();
    // the layers of a layered chunk: nine for the point, one per colour, NIR, wave packet and
    // extra byte
    let layers: u64 = vlr
        .items()
        .iter()
        .map(|item| match item.item_type() {
            LazItemType::Point14 => POINT14_LAYERS as u64,
            LazItemType::RGBNIR14 => 2,
            LazItemType::Byte14(n) => u64::from(n),
            LazItemType::RGB14 | LazItemType::WavePacket14 => 1,
            _ => 0,
        })
        .sum();
    let mut points = 0u64;
    let mut start = data;
    for (k, e) in entries.iter().enumerate() {
        let end = start.checked_add(e.byte_count).filter(|&end| end <= table && e.byte_count >= h.record_len as u64);
        let Some(end) = end else {
            return Err(err(format!(
                "chunk {} of {} has {} bytes from byte {start}: not a chunk within the compressed data (up to byte {table})",
                k + 1,
                entries.len(),
                e.byte_count
            )));
        };
        if vlr.uses_variable_size_chunks() && e.point_count == 0 {
            return Err(err(format!("chunk {} of {} holds no points", k + 1, entries.len())));
        }
        if layered {
            // the chunk: its first point, its point count, then the size of each layer of each
            // item (every layer is checked: a file may be decoded whole, `decompressed`)
            let sizes = start + h.record_len as u64 + 4;
            if sizes + 4 * layers > end {
                return Err(err(format!("chunk {} of {} is too short for its layer sizes", k + 1, entries.len())));
            }
            let total: u64 = (0..layers).map(|l| u32_at(bytes, (sizes + 4 * l) as usize) as u64).sum();
            if sizes + 4 * layers + total > end {
                return Err(err(format!(
                    "chunk {} of {}: its point's layers ({total} bytes) overrun its {} bytes",
                    k + 1,
                    entries.len(),
                    e.byte_count
                )));
            }
        }
        points = points.saturating_add(e.point_count);
        start = end;
    }
    if points < h.count {
        return Err(err(format!(
            "the header claims {} points, but the chunk table's {} chunks hold {points}",
            h.count,
            entries.len()
        )));
    }
    Ok(())
}
