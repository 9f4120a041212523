//! A glTF file moved as it is: each of its top nodes (those its scenes list, or, in a file
//! without scenes, those that are no node's child) gets a new parent node, named
//! `T_target_source`, whose `matrix` is the motion, so that every vertex, normal, animation,
//! camera and light below moves with it and no byte of its buffers changes. A GLB file keeps its
//! binary chunk and every chunk after it; its JSON is written anew (its keys in sorted order).
//! The file is read by the glTF reader first, so a file it refuses is refused here too.

use super::gltf::{as_index, list, open, roots, F};
use super::motion::Motion;
use super::Faces;
use crate::{Error, Result};
use nalgebra::Matrix4;
use serde_json::{json, Value};

/// The glTF file `bytes` with its scenes moved by `m` (`T_target_source`: a rigid transform, or
/// one times a uniform scale; see the module docs).
pub(crate) fn transform_gltf(bytes: &[u8], m: &Matrix4<f64>) -> Result<Vec<u8>> {
    Motion::new(m)?;
    super::gltf::read(bytes, Faces::Skip)?;
    let c = open(bytes)?;
    let mut doc = c.json;
    place(&mut doc, m)?;
    let mut text = serde_json::to_vec(&doc).map_err(|e| Error::parse(F, format!("cannot write its JSON: {e}")))?;
    if c.glb_length == 0 {
        return Ok(text);
    }
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let rest = &bytes[c.glb_json_end..c.glb_length];
    let total = 12 + 8 + text.len() + rest.len();
    let total32 =
        u32::try_from(total).map_err(|_| Error::TooLarge(format!("the moved {F} file would exceed 4 GiB")))?;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total32.to_le_bytes());
    out.extend_from_slice(&(text.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x4E4F_534Au32.to_le_bytes());
    out.extend_from_slice(&text);
    out.extend_from_slice(rest);
    Ok(out)
}

/// Puts `m` above every top node: each gets a new parent (see the module docs).
fn place(doc: &mut Value, m: &Matrix4<f64>) -> Result<()> {
    let mut tops: Vec<usize> = list(doc, "scenes").iter().flat_map(|s| list(s, "nodes")).filter_map(as_index).collect();
    if list(doc, "scenes").is_empty() {
        tops = roots(doc)?;
    }
    tops.sort_unstable();
    tops.dedup();
    if tops.is_empty() {
        return Ok(());
    }
    let nodes = doc.get_mut("nodes").and_then(Value::as_array_mut);
    let nodes = nodes.ok_or_else(|| Error::parse(F, "its scenes list nodes, but it has no node list"))?;
    let first = nodes.len();
    let matrix = m.as_slice(); // column-major, as glTF stores matrices
    nodes.extend(tops.iter().map(|&n| json!({ "name": "T_target_source", "matrix": matrix, "children": [n] })));
    for scene in doc.get_mut("scenes").and_then(Value::as_array_mut).into_iter().flatten() {
        for n in scene.get_mut("nodes").and_then(Value::as_array_mut).into_iter().flatten() {
            if let Some(k) = as_index(n).and_then(|n| tops.binary_search(&n).ok()) {
                *n = json!(first + k);
            }
        }
    }
    Ok(())
}
