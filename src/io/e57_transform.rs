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

/// The XML with the pose of every scan (`data3D`) and image (`images2D`) composed with `motion`
/// (`R`, `t`): the new pose maps a stored point `p` to `R (R0 p + t0) + t`.
fn moved_xml(xml: &str, rotation: UnitQuaternion<f64>, shift: Vector3<f64>) -> Result<String> {
    let doc = roxmltree::Document::parse(xml).map_err(|e| err(format!("the XML section cannot be parsed: {e}")))?;
    let mut edits: Vec<(std::ops::Range<usize>, String)> = Vec::new();
    for section in ["data3D", "images2D"] {
        let Some(list) = doc.root_element().children().find(|n| n.has_tag_name(section)) else { continue };
        for child in list.children().filter(|n| n.has_tag_name("vectorChild")) {
            let pose = child.children().find(|n| n.has_tag_name("pose"));
            let (q, t) = pose_of(pose)?;
            let xml_pose = pose_xml(rotation * q, rotation * t + shift);
            let range = match pose {
                Some(p) => p.range(),
                None => {
                    // before the child's closing tag
                    let end = child.range().end;
                    let at = xml[..end].rfind("</").filter(|&at| at >= child.range().start).ok_or_else(|| {
                        err(format!("a {section} entry without a pose has no closing tag to add one before"))
                    })?;
                    at..at
                }
            };
            edits.push((range, xml_pose));
        }
    }
    // in the file's order (an insertion sort: a few entries; the library's sorts weigh kilobytes
    // of WebAssembly)
    for i in 1..edits.len() {
        let mut j = i;
        while j > 0 && edits[j - 1].0.start > edits[j].0.start {
            edits.swap(j - 1, j);
            j -= 1;
        }
    }
    let mut out = String::with_capacity(xml.len() + 512 * edits.len());
    let mut at = 0;
    for (range, text) in edits {
        out.push_str(&xml[at..range.start]);
        out.push_str(&text);
        at = range.end;
    }
    out.push_str(&xml[at..]);
    Ok(out)
}

/// The E57 file `bytes` with every scan and image moved by `m` (`T_target_source`, rigid): their
/// poses composed with it, the points kept byte for byte (see the module docs). Errors: a file
/// the E57 reader refuses or whose pages are not whole, a motion that is not rigid (E57 poses
/// cannot hold a change of unit).
pub(crate) fn transform_e57(bytes: &[u8], m: &Matrix4<f64>) -> Result<Vec<u8>> {
    let motion = Motion::new(m)?;
    if (motion.scale() - 1.0).abs() > 1e-9 {
        return Err(Error::InvalidOption(format!(
            "an E57 file's poses are rigid: the motion's change of unit (x{}) cannot be stored; save the points instead (as PLY)",
            motion.scale()
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
    let rotation = UnitQuaternion::from_matrix(&motion.rotation);
    let xml = moved_xml(reader.xml(), rotation, motion.t)?;
    // the file, then the new XML section in pages of its own
    let xml_at = bytes.len();
    let pages = xml.len().div_ceil(DATA).max(1);
    let mut out = Vec::with_capacity(bytes.len() + pages * PAGE);
    out.extend_from_slice(bytes);
    for chunk in xml.as_bytes().chunks(DATA).chain(xml.is_empty().then_some(&[][..])) {
        let start = out.len();
        out.extend_from_slice(chunk);
        out.resize(start + PAGE, 0);
        seal(&mut out[start..start + PAGE]);
    }
    // the header (physical length, XML offset and length) and page 0's CRC
    let length = out.len() as u64;
    out[16..24].copy_from_slice(&length.to_le_bytes());
    out[24..32].copy_from_slice(&(xml_at as u64).to_le_bytes());
    out[32..40].copy_from_slice(&(xml.len() as u64).to_le_bytes());
    seal(&mut out[..PAGE]);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc32c_matches_its_check_value() {
        assert_eq!(crc32c(b"123456789"), 0xE306_9283);
    }
}
