//! glTF 2.0: binary `.glb` files, and JSON `.gltf` files whose buffers are embedded (`data:`
//! URIs). The default scene's meshes are placed by their nodes' transforms (a `matrix`, or
//! `translation`, `rotation`, `scale`, composed down the node tree, and the instances of
//! `EXT_mesh_gpu_instancing`) in `f64`, morph targets at their default weights, skinned meshes
//! posed by their joints (their node's own transform ignored, as glTF says); every primitive's
//! `POSITION`s are points, and its triangles (mode 4; strips and fans triangulated) the faces;
//! point and line primitives give points only (and nothing to a surface sample). Positions of
//! any component type, normalised or not (`KHR_mesh_quantization`), interleaved or not, and
//! sparse accessors are read. A mesh compressed by Draco or meshopt is
//! refused, naming the extension, unless the file holds it uncompressed too (the extension used,
//! not required); so is a buffer kept in another file. glTF's frame is Y-up,
//! in metres.

use super::util::u32_at;
use super::{Faces, Raw};
use crate::limits::MAX_FILE_POINTS;
use crate::{Error, Result};
use base64::Engine as _;
use nalgebra::{Matrix4, Quaternion, UnitQuaternion, Vector3};
use serde_json::Value;
use std::borrow::Cow;

pub(crate) const F: &str = "glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

fn err(message: impl Into<String>) -> Error {
    Error::parse(F, message)
}

/// True for a binary glTF file (its `glTF` magic).
pub(crate) fn is_glb(bytes: &[u8]) -> bool {
    bytes.starts_with(b"glTF")
}

/// True for a JSON glTF file: an object whose first kilobytes name its `"asset"`.
pub(crate) fn sniff_json(bytes: &[u8]) -> bool {
    let head = &bytes[..bytes.len().min(4096)];
    let head = head.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(head);
    head.trim_ascii_start().starts_with(b"{") && head.windows(7).any(|w| w == b"\"asset\"")
}

/// A glTF file taken apart: its JSON, the binary chunk of a GLB file, and where the JSON chunk
/// of a GLB file ends (the next chunk's first byte; 0 for a JSON file).
pub(crate) struct Container<'a> {
    pub(crate) json: Value,
    pub(crate) bin: Option<&'a [u8]>,
    pub(crate) glb_json_end: usize,
    pub(crate) glb_length: usize,
}

/// Splits a GLB file into its chunks, or parses a JSON file.
pub(crate) fn open(bytes: &[u8]) -> Result<Container<'_>> {
    if !is_glb(bytes) {
        let text = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
        return Ok(Container { json: parse_json(text)?, bin: None, glb_json_end: 0, glb_length: 0 });
    }
    if bytes.len() < 20 {
        return Err(err(format!(
            "a GLB file needs a 12-byte header and a JSON chunk, but the file has {} bytes",
            bytes.len()
        )));
    }
    let version = u32_at(bytes, 4);
    if version != 2 {
        return Err(err(format!("the GLB header says version {version}: only glTF 2.0 is read")));
    }
    let length = u32_at(bytes, 8) as usize;
    if length > bytes.len() {
        return Err(err(format!(
            "the GLB header declares {length} bytes, but the file has {} (is it truncated?)",
            bytes.len()
        )));
    }
    let (mut json, mut bin, mut json_end) = (None, None, 0);
    let mut at = 12;
    while at + 8 <= length {
        let (len, kind) = (u32_at(bytes, at) as usize, u32_at(bytes, at + 4));
        let start = at + 8;
        let end = start.checked_add(len).filter(|&e| e <= length).ok_or_else(|| {
            err(format!("the chunk at byte {at} declares {len} bytes, past the file's {length} (is it truncated?)"))
        })?;
        match kind {
            CHUNK_JSON if at == 12 => {
                json = Some(&bytes[start..end]);
                json_end = end;
            }
            CHUNK_BIN if bin.is_none() && json.is_some() => bin = Some(&bytes[start..end]),
            _ => {}
        }
        at = end;
    }
    let json = json.ok_or_else(|| err("the GLB file's first chunk is not its JSON"))?;
    Ok(Container { json: parse_json(json)?, bin, glb_json_end: json_end, glb_length: length })
}

fn parse_json(text: &[u8]) -> Result<Value> {
    // (from a str, as the model's metadata is parsed: one parser in the engine)
    let text = std::str::from_utf8(text).map_err(|e| err(format!("its JSON is not UTF-8: {e}")))?;
    let json: Value = serde_json::from_str(text).map_err(|e| err(format!("its JSON is malformed: {e}")))?;
    if !json.is_object() {
        return Err(err("its JSON is not an object"));
    }
    Ok(json)
}

/// `v[key]` as an array (empty when absent or not an array).
pub(crate) fn list<'v>(v: &'v Value, key: &str) -> &'v [Value] {
    v.get(key).and_then(Value::as_array).map_or(&[], Vec::as_slice)
}

/// `v[key]` as an index or count, `None` when absent; an error when it is not one.
pub(crate) fn index(v: &Value, key: &str, what: &str) -> Result<Option<usize>> {
    match v.get(key) {
        None => Ok(None),
        Some(x) => as_index(x).map(Some).ok_or_else(|| err(format!("{what}'s {key} is not a non-negative integer"))),
    }
}

/// `v` as an index (a non-negative integer that `usize` holds: one beyond 2^32 is no index in
/// wasm32, rather than cut to 32 bits).
pub(crate) fn as_index(v: &Value) -> Option<usize> {
    v.as_u64().and_then(|i| usize::try_from(i).ok())
}

fn required(v: &Value, key: &str, what: &str) -> Result<usize> {
    index(v, key, what)?.ok_or_else(|| err(format!("{what} has no {key}")))
}

/// Item `i` of the file's `key` list (`"accessors"`, ...), or an error naming what refers to it.
fn item<'v>(json: &'v Value, key: &str, i: usize, what: &str) -> Result<&'v Value> {
    let all = list(json, key);
    all.get(i).ok_or_else(|| err(format!("{what} refers to {key}[{i}], but the file has {}", all.len())))
}

/// `v[key]` as `N` numbers, or `default` when absent.
fn numbers<const N: usize>(v: &Value, key: &str, default: [f64; N], what: &str) -> Result<[f64; N]> {
    let Some(x) = v.get(key) else { return Ok(default) };
    let bad = || err(format!("{what}'s {key} is not {N} numbers"));
    let a = x.as_array().filter(|a| a.len() == N).ok_or_else(bad)?;
    let mut out = [0.0; N];
    for (o, x) in out.iter_mut().zip(a) {
        *o = x.as_f64().ok_or_else(bad)?;
    }
    Ok(out)
}

/// The file's buffers, decoded: a GLB file's binary chunk, or embedded base64 `data:` URIs.
fn buffers<'a>(c: &Container<'a>) -> Result<Vec<Cow<'a, [u8]>>> {
    let mut out = Vec::new();
    for (i, b) in list(&c.json, "buffers").iter().enumerate() {
        let bytes = match b.get("uri").and_then(Value::as_str) {
            None => match c.bin {
                Some(bin) if i == 0 => Cow::Borrowed(bin),
                _ => return Err(err(format!("buffers[{i}] has no uri, and it is not a GLB file's first buffer"))),
            },
            Some(uri) if uri.starts_with("data:") => {
                let data = uri
                    .split_once(";base64,")
                    .map(|(_, d)| d)
                    .ok_or_else(|| err(format!("buffers[{i}] is a data URI without base64 data")))?;
                let decoded = base64::engine::general_purpose::STANDARD
                    .decode(data)
                    .map_err(|e| err(format!("buffers[{i}]'s base64 data is malformed: {e}")))?;
                Cow::Owned(decoded)
            }
            Some(uri) => {
                return Err(err(format!(
                    "buffers[{i}] is another file ('{}'), which cannot be read from this one's bytes: \
                     save the model as one .glb file, or as .gltf with embedded buffers",
                    uri.chars().take(200).collect::<String>()
                )))
            }
        };
        out.push(bytes);
    }
    Ok(out)
}

/// The numeric type of an accessor's components.
#[derive(Clone, Copy)]
enum Component {
    I8,
    U8,
    I16,
    U16,
    U32,
    F32,
}

impl Component {
    fn from_code(code: usize, what: &str) -> Result<Self> {
        Ok(match code {
            5120 => Self::I8,
            5121 => Self::U8,
            5122 => Self::I16,
            5123 => Self::U16,
            5125 => Self::U32,
            5126 => Self::F32,
            _ => return Err(err(format!("{what} has componentType {code}, not one glTF defines"))),
        })
    }

    fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::U32 | Self::F32 => 4,
        }
    }

    /// The component at `b` (its first byte), scaled to [-1, 1] or [0, 1] when `normalized`.
    fn get(self, b: &[u8], normalized: bool) -> f64 {
        let (v, max) = match self {
            Self::I8 => (b[0] as i8 as f64, 127.0),
            Self::U8 => (b[0] as f64, 255.0),
            Self::I16 => (i16::from_le_bytes([b[0], b[1]]) as f64, 32767.0),
            Self::U16 => (u16::from_le_bytes([b[0], b[1]]) as f64, 65535.0),
            Self::U32 => return u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Self::F32 => return f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
        };
        if normalized {
            (v / max).max(-1.0)
        } else {
            v
        }
    }
}

/// What the readers of accessors need: the JSON and the decoded buffers.
struct Doc<'j, 'a> {
    json: &'j Value,
    buffers: Vec<Cow<'a, [u8]>>,
}

impl Doc<'_, '_> {
    /// The bytes of buffer view `v`, and its stride (`None`: tightly packed).
    fn view(&self, v: usize, what: &str) -> Result<(&[u8], Option<usize>)> {
        let view = item(self.json, "bufferViews", v, what)?;
        let vw = format!("bufferViews[{v}]");
        if view.get("extensions").and_then(|e| e.get("EXT_meshopt_compression")).is_some() {
            return Err(compressed("EXT_meshopt_compression"));
        }
        let buffer = required(view, "buffer", &vw)?;
        let data = self
            .buffers
            .get(buffer)
            .ok_or_else(|| err(format!("{vw} refers to buffers[{buffer}], but the file has {}", self.buffers.len())))?;
        let offset = index(view, "byteOffset", &vw)?.unwrap_or(0);
        let length = required(view, "byteLength", &vw)?;
        let bytes = offset.checked_add(length).and_then(|end| data.get(offset..end)).ok_or_else(|| {
            err(format!("{vw} (bytes {offset} to {offset}+{length}) lies outside its buffer of {} bytes", data.len()))
        })?;
        Ok((bytes, index(view, "byteStride", &vw)?))
    }

    /// Accessor `a` as `comps` numbers per element, flattened; `what` names its use in errors.
    fn values(&self, a: usize, comps: usize, what: &str) -> Result<Vec<f64>> {
        let acc = item(self.json, "accessors", a, what)?;
        let aw = format!("accessors[{a}] ({what})");
        let kind = acc.get("type").and_then(Value::as_str).unwrap_or("");
        let have = match kind {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            "VEC4" | "MAT2" => 4,
            "MAT3" => 9,
            "MAT4" => 16,
            _ => 0,
        };
        if have != comps {
            return Err(err(format!("{aw} has type '{kind}', where {comps} components per element are expected")));
        }
        let component = Component::from_code(required(acc, "componentType", &aw)?, &aw)?;
        let normalized = acc.get("normalized").and_then(Value::as_bool).unwrap_or(false);
        let count = required(acc, "count", &aw)?;
        let element = comps * component.size();
        let mut out = match index(acc, "bufferView", &aw)? {
            Some(v) => {
                let (bytes, stride) = self.view(v, &aw)?;
                let stride = stride.unwrap_or(element);
                let offset = index(acc, "byteOffset", &aw)?.unwrap_or(0);
                if stride < element {
                    return Err(err(format!(
                        "{aw}: its view's byteStride {stride} is less than an element's {element} bytes"
                    )));
                }
                // checked: a stride or count near 2^64 wraps the product past the size check
                let need = (count as u64)
                    .saturating_sub(1)
                    .checked_mul(stride as u64)
                    .and_then(|v| v.checked_add(element as u64 + offset as u64))
                    .unwrap_or(u64::MAX);
                if count > 0 && need > bytes.len() as u64 {
                    return Err(err(format!(
                        "{aw}: {count} elements of {element} bytes every {stride} from byte {offset} need {need} bytes, \
                         but its view has {}",
                        bytes.len()
                    )));
                }
                let mut out = Vec::with_capacity(count * comps);
                for k in 0..count {
                    let at = offset + k * stride;
                    for c in 0..comps {
                        let b = at + c * component.size();
                        out.push(component.get(&bytes[b..b + component.size()], normalized));
                    }
                }
                out
            }
            None if count <= MAX_FILE_POINTS => vec![0.0; count * comps],
            None => return Err(err(format!("{aw} has {count} elements and no data"))),
        };
        if let Some(sparse) = acc.get("sparse") {
            self.sparse(sparse, &mut out, comps, component, normalized, &aw)?;
        }
        Ok(out)
    }

    /// Applies an accessor's sparse substitutions to its values `out`.
    fn sparse(
        &self,
        sparse: &Value,
        out: &mut [f64],
        comps: usize,
        component: Component,
        normalized: bool,
        aw: &str,
    ) -> Result<()> {
        let sw = format!("{aw}'s sparse");
        let n = required(sparse, "count", &sw)?;
        let (Some(indices), Some(values)) = (sparse.get("indices"), sparse.get("values")) else {
            return Err(err(format!("{sw} lacks its indices or values")));
        };
        let index_kind = Component::from_code(required(indices, "componentType", &sw)?, &sw)?;
        let read = |part: &Value, size: usize| -> Result<&[u8]> {
            let (bytes, _) = self.view(required(part, "bufferView", &sw)?, &sw)?;
            let offset = index(part, "byteOffset", &sw)?.unwrap_or(0);
            offset
                .checked_add(n.saturating_mul(size))
                .and_then(|end| bytes.get(offset..end))
                .ok_or_else(|| err(format!("{sw}: {n} entries of {size} bytes from byte {offset} overrun their view")))
        };
        let at = read(indices, index_kind.size())?;
        let element = comps * component.size();
        let vals = read(values, element)?;
        let elements = out.len() / comps.max(1);
        for k in 0..n {
            let i = index_kind.get(&at[k * index_kind.size()..], false) as usize;
            // compared before multiplying (`i * comps` wraps in wasm32's usize for i near 2^32)
            let slot = (i < elements)
                .then(|| out.get_mut(i * comps..(i + 1) * comps))
                .flatten()
                .ok_or_else(|| err(format!("{sw}: index {i} is beyond the accessor's {elements} elements")))?;
            for (c, s) in slot.iter_mut().enumerate() {
                let b = k * element + c * component.size();
                *s = component.get(&vals[b..], normalized);
            }
        }
        Ok(())
    }
}

fn compressed(extension: &str) -> Error {
    err(format!(
        "the model is compressed with {extension}, which arps does not decode: save it without that compression \
         (e.g. in Blender, or `gltf-transform copy` after decoding)"
    ))
}

/// A node's own transform: its `matrix` (column-major), else translation * rotation * scale.
fn local(node: &Value, what: &str) -> Result<Matrix4<f64>> {
    if node.get("matrix").is_some() {
        let m = numbers::<16>(node, "matrix", [0.0; 16], what)?;
        return Ok(Matrix4::from_column_slice(&m));
    }
    let [tx, ty, tz] = numbers(node, "translation", [0.0; 3], what)?;
    let [x, y, z, w] = numbers(node, "rotation", [0.0, 0.0, 0.0, 1.0], what)?;
    let [sx, sy, sz] = numbers(node, "scale", [1.0; 3], what)?;
    Ok(trs(Vector3::new(tx, ty, tz), Quaternion::new(w, x, y, z), Vector3::new(sx, sy, sz)))
}

/// `T * R * S`; a zero quaternion turns nothing.
fn trs(t: Vector3<f64>, q: Quaternion<f64>, s: Vector3<f64>) -> Matrix4<f64> {
    let r = if q.norm() > 0.0 { UnitQuaternion::from_quaternion(q).to_homogeneous() } else { Matrix4::identity() };
    Matrix4::new_translation(&t) * r * Matrix4::new_nonuniform_scaling(&s)
}

/// The nodes at the top of the scene read: the `scene`'s (else the first scene's) nodes, or, in
/// a file without scenes, every node that is no other node's child.
pub(crate) fn roots(json: &Value) -> Result<Vec<usize>> {
    let scenes = list(json, "scenes");
    let scene = index(json, "scene", "the file")?.or(if scenes.is_empty() { None } else { Some(0) });
    let Some(s) = scene else {
        return Ok(parents(json).iter().enumerate().filter(|(_, p)| p.is_none()).map(|(i, _)| i).collect());
    };
    let scene = item(json, "scenes", s, "the file's scene")?;
    list(scene, "nodes")
        .iter()
        .map(|n| as_index(n).ok_or_else(|| err(format!("scenes[{s}]'s nodes are not indices"))))
        .collect()
}

/// The instance transforms of a node's `EXT_mesh_gpu_instancing`, or the identity alone.
fn instances(doc: &Doc, node: &Value, what: &str) -> Result<Vec<Matrix4<f64>>> {
    let Some(ext) = node.get("extensions").and_then(|e| e.get("EXT_mesh_gpu_instancing")) else {
        return Ok(vec![Matrix4::identity()]);
    };
    let attrs = ext.get("attributes").cloned().unwrap_or(Value::Null);
    let read = |name: &str, comps: usize| -> Result<Option<Vec<f64>>> {
        index(&attrs, name, what)?.map(|a| doc.values(a, comps, &format!("{what}'s instance {name}"))).transpose()
    };
    let (t, r, s) = (read("TRANSLATION", 3)?, read("ROTATION", 4)?, read("SCALE", 3)?);
    let n = [t.as_ref().map(|v| v.len() / 3), r.as_ref().map(|v| v.len() / 4), s.as_ref().map(|v| v.len() / 3)];
    let count = n.iter().flatten().copied().min().unwrap_or(0);
    if n.iter().flatten().any(|&k| k != count) {
        return Err(err(format!("{what}'s instance attributes differ in count")));
    }
    Ok((0..count)
        .map(|k| {
            let v3 = |v: &Option<Vec<f64>>, d: f64| {
                v.as_ref().map_or(Vector3::repeat(d), |v| Vector3::new(v[3 * k], v[3 * k + 1], v[3 * k + 2]))
            };
            let q = r.as_ref().map_or(Quaternion::identity(), |v| {
                Quaternion::new(v[4 * k + 3], v[4 * k], v[4 * k + 1], v[4 * k + 2])
            });
            trs(v3(&t, 0.0), q, v3(&s, 1.0))
        })
        .collect())
}

/// Reads the default scene's meshes, placed (see the module docs); triangles unless `faces` is
/// [`Faces::Skip`], at most as many as the file has bytes (or 2^20) once placed (a mesh placed by
/// many nodes repeats its own).
pub(crate) fn read(bytes: &[u8], faces: Faces) -> Result<Raw> {
    let c = open(bytes)?;
    for ext in list(&c.json, "extensionsRequired").iter().filter_map(Value::as_str) {
        if ext == "KHR_draco_mesh_compression" || ext.contains("meshopt_compression") {
            return Err(compressed(ext));
        }
    }
    let doc = Doc { json: &c.json, buffers: buffers(&c)? };
    let nodes = list(&c.json, "nodes");
    // every node's place in the scene (joints may lie outside the scene's tree), then the meshes
    // of the scene's nodes, in the tree's order
    let world = world_transforms(&c.json)?;
    let mut seen = vec![false; nodes.len()];
    let mut stack: Vec<usize> = roots(&c.json)?.into_iter().rev().collect();
    let (mut vertices, mut triangles) = (Vec::new(), Vec::new());
    let triangle_limit = bytes.len().max(1 << 20);
    while let Some(n) = stack.pop() {
        let nw = format!("nodes[{n}]");
        let node = item(&c.json, "nodes", n, "a scene or node")?;
        if std::mem::replace(&mut seen[n], true) {
            return Err(err(format!("{nw} is reached twice (a node has one parent, and the tree no cycle)")));
        }
        if let Some(m) = index(node, "mesh", &nw)? {
            let mesh = item(&c.json, "meshes", m, &nw)?;
            // morph targets' default weights: the node's, else the mesh's
            let weights = if node.get("weights").is_some() { list(node, "weights") } else { list(mesh, "weights") };
            let weights: Vec<f64> = weights.iter().map(|w| w.as_f64().unwrap_or(0.0)).collect();
            let places = match index(node, "skin", &nw)? {
                Some(s) => vec![Place::Skin(skin(&doc, &world, s, &nw)?)],
                None => instances(&doc, node, &nw)?.into_iter().map(|i| Place::Rigid(world[n] * i)).collect(),
            };
            for place in &places {
                for (p, prim) in list(mesh, "primitives").iter().enumerate() {
                    let pw = format!("meshes[{m}].primitives[{p}]");
                    let at = Placing { place, fallback: &world[n], weights: &weights };
                    primitive(&doc, prim, &pw, &at, faces, &mut vertices, &mut triangles)?;
                    if triangles.len() > triangle_limit {
                        return Err(Error::TooLarge(format!(
                            "the {F} file's scene holds more than {triangle_limit} triangles once its meshes are placed"
                        )));
                    }
                }
            }
        }
        for child in list(node, "children").iter().rev() {
            let child = as_index(child).filter(|&c| c < nodes.len());
            stack.push(child.ok_or_else(|| err(format!("{nw}'s children are not indices of its nodes")))?);
        }
    }
    if vertices.is_empty() && !list(&c.json, "meshes").is_empty() {
        return Err(err(format!(
            "its default scene draws none of its {} meshes (another scene may: arps reads the default one)",
            list(&c.json, "meshes").len()
        )));
    }
    Ok(Raw { vertices, triangles })
}

/// Each node's parent (the last node that lists it among its children), `None` for a top node.
fn parents(json: &Value) -> Vec<Option<usize>> {
    let nodes = list(json, "nodes");
    let mut parent = vec![None; nodes.len()];
    for (i, node) in nodes.iter().enumerate() {
        for c in list(node, "children").iter().filter_map(as_index) {
            if let Some(p) = parent.get_mut(c) {
                *p = Some(i);
            }
        }
    }
    parent
}

/// Every node's world transform (its ancestors' times its own); a node in a cycle is an error.
fn world_transforms(json: &Value) -> Result<Vec<Matrix4<f64>>> {
    let nodes = list(json, "nodes");
    let parent = parents(json);
    let mut world: Vec<Option<Matrix4<f64>>> = vec![None; nodes.len()];
    for start in 0..nodes.len() {
        if world[start].is_some() {
            continue;
        }
        // up to the nearest ancestor already placed, then down again
        let mut chain = vec![start];
        while let Some(p) = parent[*chain.last().unwrap_or(&start)].filter(|&p| world[p].is_none()) {
            if chain.len() > nodes.len() {
                return Err(err(format!("nodes[{start}]'s ancestors form a cycle")));
            }
            chain.push(p);
        }
        for &n in chain.iter().rev() {
            if world[n].is_none() {
                let above = parent[n].and_then(|p| world[p]).unwrap_or_else(Matrix4::identity);
                world[n] = Some(above * local(&nodes[n], &format!("nodes[{n}]"))?);
            }
        }
    }
    Ok(world.into_iter().map(|w| w.unwrap_or_else(Matrix4::identity)).collect())
}

/// How a mesh is placed: rigidly (its node, an instance), or by a skin's joints.
enum Place {
    Rigid(Matrix4<f64>),
    /// Each joint's world transform times its inverse bind matrix.
    Skin(Vec<Matrix4<f64>>),
}

/// A primitive's placing: its mesh's place, the node's transform for a skinned primitive without
/// joints, and the morph targets' weights.
struct Placing<'a> {
    place: &'a Place,
    fallback: &'a Matrix4<f64>,
    weights: &'a [f64],
}

/// The joint matrices of skin `s`: each joint's world transform times its inverse bind matrix.
fn skin(doc: &Doc, world: &[Matrix4<f64>], s: usize, what: &str) -> Result<Vec<Matrix4<f64>>> {
    let skin = item(doc.json, "skins", s, what)?;
    let sw = format!("skins[{s}]");
    let joints: Vec<usize> = list(skin, "joints")
        .iter()
        .map(|j| as_index(j).filter(|&j| j < world.len()))
        .collect::<Option<_>>()
        .ok_or_else(|| err(format!("{sw}'s joints are not indices of its nodes")))?;
    let inverse = match index(skin, "inverseBindMatrices", &sw)? {
        Some(a) => doc.values(a, 16, &format!("{sw} inverseBindMatrices"))?,
        None => Matrix4::<f64>::identity().as_slice().repeat(joints.len()),
    };
    if inverse.len() != 16 * joints.len() {
        return Err(err(format!("{sw} has {} joints but {} inverse bind matrices", joints.len(), inverse.len() / 16)));
    }
    Ok(joints.iter().zip(inverse.chunks_exact(16)).map(|(&j, m)| world[j] * Matrix4::from_column_slice(m)).collect())
}

/// Appends a primitive's points, placed by `at`, and its triangles.
fn primitive(
    doc: &Doc,
    prim: &Value,
    pw: &str,
    at: &Placing,
    faces: Faces,
    vertices: &mut Vec<[f64; 3]>,
    triangles: &mut Vec<[u32; 3]>,
) -> Result<()> {
    let attributes = prim.get("attributes").unwrap_or(&Value::Null);
    let Some(position) = index(attributes, "POSITION", pw)? else {
        return Ok(()); // nothing to draw
    };
    // Draco: the extension used, not required, leaves the data uncompressed too (accessors with
    // views); without them there is nothing to read
    let draco = prim.get("extensions").and_then(|e| e.get("KHR_draco_mesh_compression")).is_some();
    if draco && doc.json["accessors"][position].get("bufferView").is_none() {
        return Err(compressed("KHR_draco_mesh_compression"));
    }
    let mut xyz = doc.values(position, 3, &format!("{pw} POSITION"))?;
    let count = xyz.len() / 3;
    // morph targets at their default weights
    for (k, target) in list(prim, "targets").iter().enumerate() {
        let w = at.weights.get(k).copied().unwrap_or(0.0);
        if let (Some(a), true) = (index(target, "POSITION", pw)?, w != 0.0) {
            let d = doc.values(a, 3, &format!("{pw} morph target {k}"))?;
            if d.len() != xyz.len() {
                return Err(err(format!("{pw}: morph target {k} has {} positions, not {count}", d.len() / 3)));
            }
            xyz.iter_mut().zip(&d).for_each(|(x, d)| *x += w * d);
        }
    }
    let base = vertices.len();
    crate::limits::check_file_points(F, (base + count) as u64)?;
    let moved = |m: &Matrix4<f64>, p: &[f64]| {
        let q = m * nalgebra::Vector4::new(p[0], p[1], p[2], 1.0);
        [q.x, q.y, q.z]
    };
    match (at.place, index(attributes, "JOINTS_0", pw)?, index(attributes, "WEIGHTS_0", pw)?) {
        (Place::Skin(joints), Some(j), Some(w)) => {
            let (j, w) = (doc.values(j, 4, &format!("{pw} JOINTS_0"))?, doc.values(w, 4, &format!("{pw} WEIGHTS_0"))?);
            if j.len() != 4 * count || w.len() != 4 * count {
                return Err(err(format!("{pw}: JOINTS_0 and WEIGHTS_0 do not have one entry per vertex")));
            }
            for (i, p) in xyz.chunks_exact(3).enumerate() {
                let mut m = Matrix4::zeros();
                for k in 4 * i..4 * i + 4 {
                    let joint = joints.get(j[k] as usize).ok_or_else(|| {
                        err(format!("{pw}: vertex {i} names joint {}, beyond its skin's {}", j[k], joints.len()))
                    })?;
                    m += joint * w[k];
                }
                vertices.push(moved(&m, p));
            }
        }
        (Place::Skin(_), _, _) => vertices.extend(xyz.chunks_exact(3).map(|p| moved(at.fallback, p))),
        (Place::Rigid(m), _, _) => vertices.extend(xyz.chunks_exact(3).map(|p| moved(m, p))),
    }
    let mode = index(prim, "mode", pw)?.unwrap_or(4);
    if faces == Faces::Skip || !(4..=6).contains(&mode) {
        return Ok(());
    }
    let order: Vec<usize> = match index(prim, "indices", pw)? {
        Some(a) => {
            let raw = doc.values(a, 1, &format!("{pw} indices"))?;
            let mut order = Vec::with_capacity(raw.len());
            for i in raw {
                if !(i >= 0.0 && (i as usize) < count) {
                    return Err(err(format!("{pw}: vertex index {i} is out of range ({count} vertices)")));
                }
                order.push(i as usize);
            }
            order
        }
        None => (0..count).collect(),
    };
    let tri = |a: usize, b: usize, c: usize| [a, b, c].map(|i| (base + order[i]) as u32);
    match mode {
        4 => triangles.extend((0..order.len() / 3).map(|k| tri(3 * k, 3 * k + 1, 3 * k + 2))),
        5 => {
            triangles
                .extend((2..order.len()).map(|k| if k % 2 == 0 { tri(k - 2, k - 1, k) } else { tri(k - 2, k, k - 1) }))
        }
        _ => triangles.extend((2..order.len()).map(|k| tri(0, k - 1, k))),
    }
    Ok(())
}
