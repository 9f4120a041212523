//! An E57 file moved as it is: every scan's pose (and every image's) composed with the motion,
//! every point left as it was stored. E57 stores each scan in its scanner's frame with a rigid
//! pose into the file's frame, so moving the file's contents is a matter of its XML: the poses
//! are rewritten there, and the binary sections (points, images, their CRCs) are kept byte for
//! byte.
//!
//! The file is E57's paged layout (pages of 1,024 bytes, the last four a CRC-32C of the rest): the
//! new XML section is appended after the last page, in pages of its own, and the header (in page
//! 0) points to it; the old XML section stays behind, unreferenced. A pose can only be rigid, so
//! a motion with a change of unit is refused: save such a source's points instead.
//!
//! One scan of a file of several is saved as a file of its own ([`transform_e57_scan`]): the
//! pages of its points' section, and of its images' (those associated with the scan), are copied
//! as they are into a new file (the images' after its header page, then the XML, then the
//! points'), their offsets in the XML and in the points' section header moved with them, and
//! the XML lists that scan and those images alone.

use super::motion::Motion;
use crate::{Error, Result};
use nalgebra::{Matrix4, Quaternion, UnitQuaternion, Vector3};

const FORMAT: &str = "E57";
/// E57's page: 1,020 bytes of data, then their CRC-32C (stored big-endian).
const PAGE: usize = 1024;
const DATA: usize = PAGE - 4;

fn err(message: impl Into<String>) -> Error {
    Error::parse(FORMAT, message.into())
}

/// CRC-32C (Castagnoli), as E57 checks its pages.
fn crc32c(data: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in data {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 { (crc >> 1) ^ 0x82F6_3B78 } else { crc >> 1 };
        }
    }
    !crc
}

/// Writes the CRC of `page`'s data into its last four bytes.
fn seal(page: &mut [u8]) {
    let crc = crc32c(&page[..DATA]);
    page[DATA..PAGE].copy_from_slice(&crc.to_be_bytes());
}

/// A `<pose>` element's rotation and translation (identity for what it leaves out; an element
/// without text is 0, as the e57 crate reads it).
fn pose_of(node: Option<roxmltree::Node>) -> Result<(UnitQuaternion<f64>, Vector3<f64>)> {
    let Some(node) = node else { return Ok((UnitQuaternion::identity(), Vector3::zeros())) };
    let part = |name: &str| node.children().find(|c| c.has_tag_name(name));
    let value = |parent: Option<roxmltree::Node>, name: &str, default: f64| -> Result<f64> {
        let Some(n) = parent.and_then(|p| p.children().find(|c| c.has_tag_name(name))) else { return Ok(default) };
        let text = n.text().unwrap_or("0").trim();
        text.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| {
            err(format!("a pose's {name} is '{}', not a finite number", text.chars().take(40).collect::<String>()))
        })
    };
    let (r, t) = (part("rotation"), part("translation"));
    let q = Quaternion::new(value(r, "w", 1.0)?, value(r, "x", 0.0)?, value(r, "y", 0.0)?, value(r, "z", 0.0)?);
    if q.norm() <= 1e-12 {
        return Err(err("a pose's rotation is the zero quaternion"));
    }
    let t = Vector3::new(value(t, "x", 0.0)?, value(t, "y", 0.0)?, value(t, "z", 0.0)?);
    Ok((UnitQuaternion::from_quaternion(q), t))
}

/// A `<pose>` element (rotation as a quaternion with `w >= 0`, as E57 asks, and translation).
fn pose_xml(q: UnitQuaternion<f64>, t: Vector3<f64>) -> String {
    let q = if q.w < 0.0 { -q.into_inner() } else { q.into_inner() };
    let f = |name: &str, v: f64| format!("<{name} type=\"Float\">{v}</{name}>");
    format!(
        "<pose type=\"Structure\"><rotation type=\"Structure\">{}{}{}{}</rotation><translation type=\"Structure\">{}{}{}</translation></pose>",
        f("w", q.w),
        f("x", q.i),
        f("y", q.j),
        f("z", q.k),
        f("x", t.x),
        f("y", t.y),
        f("z", t.z)
    )
}

fn parse(xml: &str) -> Result<roxmltree::Document<'_>> {
    roxmltree::Document::parse(xml).map_err(|e| err(format!("the XML section cannot be parsed: {e}")))
}

/// The entries (`vectorChild`) of the root's list `section` (`data3D`: the scans; `images2D`).
fn entries<'a, 'i>(doc: &'a roxmltree::Document<'i>, section: &str) -> Vec<roxmltree::Node<'a, 'i>> {
    let list = doc.root_element().children().find(|n| n.has_tag_name(section));
    list.map(|l| l.children().filter(|n| n.has_tag_name("vectorChild")).collect()).unwrap_or_default()
}

/// The text of an entry's child element `name` (its `guid`, say).
fn child_text<'a>(entry: roxmltree::Node<'a, '_>, name: &str) -> Option<&'a str> {
    entry.children().find(|n| n.has_tag_name(name)).and_then(|n| n.text()).map(str::trim)
}

/// The edit that composes an entry's pose with the motion (`rotation`, `shift`): the new pose maps
/// a stored point `p` to `R (R0 p + t0) + t`. An entry without a pose (the identity) gets one.
fn pose_edit(
    xml: &str,
    entry: roxmltree::Node,
    section: &str,
    rotation: UnitQuaternion<f64>,
    shift: Vector3<f64>,
) -> Result<(std::ops::Range<usize>, String)> {
    let pose = entry.children().find(|n| n.has_tag_name("pose"));
    let (q, t) = pose_of(pose)?;
    let range = match pose {
        Some(p) => p.range(),
        None => {
            // before the entry's closing tag
            let end = entry.range().end;
            let at = xml[..end]
                .rfind("</")
                .filter(|&at| at >= entry.range().start)
                .ok_or_else(|| err(format!("a {section} entry without a pose has no closing tag to add one before")))?;
            at..at
        }
    };
    Ok((range, pose_xml(rotation * q, rotation * t + shift)))
}

/// `xml` with each of the (disjoint) `edits`' ranges replaced by its text.
fn edited(xml: &str, mut edits: Vec<(std::ops::Range<usize>, String)>) -> String {
    super::util::in_text_order(&mut edits, |e| e.0.start);
    let mut out = String::with_capacity(xml.len() + 512 * edits.len());
    let mut at = 0;
    for (range, text) in edits {
        out.push_str(&xml[at..range.start]);
        out.push_str(&text);
        at = range.end;
    }
    out.push_str(&xml[at..]);
    out
}

/// The E57 file `bytes` with every scan and image moved by `m` (`T_target_source`, rigid): their
/// poses composed with it, the points kept byte for byte (see the module docs). Errors: a file
/// the E57 reader refuses or whose pages are not whole, a motion that is not rigid (E57 poses
/// cannot hold a change of unit).
pub(crate) fn transform_e57(bytes: &[u8], m: &Matrix4<f64>) -> Result<Vec<u8>> {
    let (xml, rotation, shift) = prepare(bytes, m)?;
    let doc = parse(&xml)?;
    let mut edits = Vec::new();
    for section in ["data3D", "images2D"] {
        for child in entries(&doc, section) {
            edits.push(pose_edit(&xml, child, section, rotation, shift)?);
        }
    }
    let xml = edited(&xml, edits);
    // the file, then the new XML section in pages of its own
    Ok(finish(bytes.to_vec(), &xml, &[]))
}

/// The checks both movers share (a rigid motion; a file the E57 reader opens, in whole pages of
/// 1,024 bytes): the file's XML section and the motion's rotation and translation.
fn prepare(bytes: &[u8], m: &Matrix4<f64>) -> Result<(String, UnitQuaternion<f64>, Vector3<f64>)> {
    let motion = Motion::new(m)?;
    if (motion.scale() - 1.0).abs() > 1e-9 {
        return Err(Error::InvalidOption(format!(
            "an E57 file's poses are rigid: the motion's change of unit (x{}) cannot be stored; save the points instead (as PLY)",
            motion.scale()
        )));
    }
    // a pose applies the nearest rotation about the file's origin, which on a map grid lies far
    // from the points: a matrix only nearly rigid would move them where the matrix does not
    let off = (motion.linear - motion.rotation).abs().max();
    if off > 1e-9 {
        return Err(Error::InvalidOption(format!(
            "an E57 file's poses are rigid: this matrix is {} off the rotation nearest it (written with few decimals, \
             or a scale near 1), which a pose would apply about the file's origin rather than where the points are; \
             give it rigid to 1e-9 (a registration's T_target_source is), or save the points instead (as PLY)",
            crate::error::num(off)
        )));
    }
    let reader = super::e57::open(bytes)?;
    let header = reader.header();
    if header.page_size != PAGE as u64 || header.phys_length != bytes.len() as u64 || !bytes.len().is_multiple_of(PAGE)
    {
        return Err(err(format!(
            "the header says {} bytes in pages of {}, the file has {} bytes: not whole pages of 1,024",
            header.phys_length,
            header.page_size,
            bytes.len()
        )));
    }
    Ok((reader.xml().to_string(), UnitQuaternion::from_matrix(&motion.rotation), motion.t))
}

/// The pages an XML section of `len` bytes takes.
fn xml_pages(len: usize) -> usize {
    len.div_ceil(DATA).max(1)
}

/// `out` (whole pages, the first the file's header page) with the XML section `xml` appended in
/// pages of its own, then `tail` (whole pages), and the header (physical length, the XML's
/// offset and length) saying so.
fn finish(mut out: Vec<u8>, xml: &str, tail: &[u8]) -> Vec<u8> {
    let xml_at = out.len();
    out.reserve(xml_pages(xml.len()) * PAGE + tail.len());
    for chunk in xml.as_bytes().chunks(DATA).chain(xml.is_empty().then_some(&[][..])) {
        let start = out.len();
        out.extend_from_slice(chunk);
        out.resize(start + PAGE, 0);
        seal(&mut out[start..start + PAGE]);
    }
    out.extend_from_slice(tail);
    // the header (physical length, XML offset and length) and page 0's CRC
    let length = out.len() as u64;
    out[16..24].copy_from_slice(&length.to_le_bytes());
    out[24..32].copy_from_slice(&(xml_at as u64).to_le_bytes());
    out[32..40].copy_from_slice(&(xml.len() as u64).to_le_bytes());
    seal(&mut out[..PAGE]);
    out
}

/// The E57 file `bytes`' scan `scan` (0-based, in the file's order) alone, moved by `m`
/// (`T_target_source`, rigid), as a file of its own: its points' section and its images' (the
/// `images2D` entries whose `associatedData3DGuid` is the scan's `guid`) copied page by page, the
/// XML listing only them, with their poses composed with the motion (see the module docs).
/// Errors: those of [`transform_e57`], a scan beyond the file's, a binary section the XML places
/// outside the file.
pub(crate) fn transform_e57_scan(bytes: &[u8], scan: usize, m: &Matrix4<f64>) -> Result<Vec<u8>> {
    let (xml, rotation, shift) = prepare(bytes, m)?;
    let doc = parse(&xml)?;
    let scans = entries(&doc, "data3D");
    let Some(&chosen) = scans.get(scan) else {
        return Err(Error::InvalidOption(format!(
            "scan = {scan}, but the E57 file holds {} scans{}",
            scans.len(),
            if scans.is_empty() { String::new() } else { format!(" (0 to {})", scans.len() - 1) }
        )));
    };
    let guid = child_text(chosen, "guid");
    let images = entries(&doc, "images2D");
    let (kept, dropped): (Vec<_>, Vec<_>) =
        images.into_iter().partition(|image| guid.is_some() && child_text(*image, "associatedData3DGuid") == guid);
    let mut edits: Vec<(std::ops::Range<usize>, String)> = Vec::new();
    // the other scans and images left out
    for entry in scans.iter().enumerate().filter(|(k, _)| *k != scan).map(|(_, e)| e).chain(&dropped) {
        edits.push((entry.range(), String::new()));
    }
    // the header page, then the kept entries' blobs (their images), copied; their points'
    // sections (compressed vectors) later
    let mut out = bytes[..PAGE].to_vec();
    let mut vectors = Vec::new();
    for (entry, section) in std::iter::once((chosen, "data3D")).chain(kept.into_iter().map(|i| (i, "images2D"))) {
        edits.push(pose_edit(&xml, entry, section, rotation, shift)?);
        for node in entry.descendants() {
            let Some(attribute) = node.attributes().find(|a| a.name() == "fileOffset") else { continue };
            let offset = attribute.value().trim().parse::<u64>().map_err(|_| {
                err(format!(
                    "a {} element's fileOffset '{}' is not an offset",
                    node.tag_name().name(),
                    attribute.value()
                ))
            })?;
            if node.attribute("type") == Some("CompressedVector") {
                vectors.push((attribute.range(), offset));
            } else {
                let moved = copy_section(bytes, offset, false, &mut out, 0)?;
                edits.push((attribute.range(), format!("fileOffset=\"{moved}\"")));
            }
        }
    }
    // The points' sections go last, after the XML: a reader runs through a compressed vector's
    // packets until it has its records, whatever the section's length says, so in a file whose
    // packets fall short of them it meets the file's end (an error), as it could not in the
    // original's other bytes. Their offsets depend on the XML's pages, which their offsets'
    // digits may change: planned until the two agree.
    let xml_at = out.len();
    let mut pages = xml_pages(xml.len());
    for _ in 0..4 {
        let base = (xml_at + pages * PAGE) as u64;
        let (mut tail, mut all) = (Vec::new(), edits.clone());
        for (range, offset) in &vectors {
            let moved = copy_section(bytes, *offset, true, &mut tail, base)?;
            all.push((range.clone(), format!("fileOffset=\"{moved}\"")));
        }
        let new_xml = edited(&xml, all);
        if xml_pages(new_xml.len()) == pages {
            return Ok(finish(out, &new_xml, &tail));
        }
        pages = xml_pages(new_xml.len());
    }
    Err(err("the XML section's length does not settle"))
}

/// Where physical byte `p` lies among the pages' data bytes (E57's logical offset), and back.
fn logical(p: u64) -> u64 {
    p / PAGE as u64 * DATA as u64 + p % PAGE as u64
}

fn physical(l: u64) -> u64 {
    l / DATA as u64 * PAGE as u64 + l % DATA as u64
}

/// The binary section at physical offset `at` of `bytes` (a compressed vector's, which holds the
/// physical offsets of its data and index packets, or a blob's) copied to the end of `out`
/// (whole pages, to lie at physical offset `base` of the new file) with the pages it spans,
/// where it keeps its place within its page; in a compressed vector's header the data's offset
/// moved with it and the index's cleared (index packets, optional, hold offsets too; readers go
/// through the data in order). Returns its new physical offset.
fn copy_section(bytes: &[u8], at: u64, compressed: bool, out: &mut Vec<u8>, base: u64) -> Result<u64> {
    let header_len: u64 = if compressed { 32 } else { 16 };
    let outside = || err(format!("a binary section at byte {at} does not lie within the file's {} bytes", bytes.len()));
    let len = bytes.len() as u64;
    if at >= len || at % PAGE as u64 >= DATA as u64 || physical(logical(at) + header_len - 1) >= len {
        return Err(outside());
    }
    let byte = |l: u64| bytes[physical(l) as usize];
    let read_u64 = |l: u64| u64::from_le_bytes(std::array::from_fn(|i| byte(l + i as u64)));
    let start = logical(at);
    let section_len = read_u64(start + 8).max(header_len);
    // (a section no longer than the file keeps the arithmetic below far from overflowing)
    let last = (section_len <= len).then(|| physical(start + section_len - 1)).filter(|&p| p < len);
    let last = last.ok_or_else(outside)?;
    let (first_page, last_page) = (at / PAGE as u64, last / PAGE as u64);
    let new_first = (base + out.len() as u64) / PAGE as u64;
    out.extend_from_slice(&bytes[(first_page * PAGE as u64) as usize..((last_page + 1) * PAGE as u64) as usize]);
    let moved = at - first_page * PAGE as u64 + new_first * PAGE as u64;
    if compressed {
        let data = read_u64(start + 16);
        if data < at || data > last {
            return Err(err(format!(
                "a compressed vector at byte {at} has its data at byte {data}, outside the section"
            )));
        }
        let new_start = logical(moved);
        let mut patch = [0u8; 16];
        patch[..8].copy_from_slice(&(data - at + moved).to_le_bytes());
        for (i, b) in patch.iter().enumerate() {
            out[(physical(new_start + 16 + i as u64) - base) as usize] = *b;
        }
        for p in [physical(new_start + 16), physical(new_start + 31)] {
            let page = ((p - base) / PAGE as u64) as usize * PAGE;
            seal(&mut out[page..page + PAGE]);
        }
    }
    Ok(moved)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc32c_matches_its_check_value() {
        assert_eq!(crc32c(b"123456789"), 0xE306_9283);
    }
}
