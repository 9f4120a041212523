//! glTF and GLB: a scene's meshes placed by their nodes, on files written by trimesh and
//! gltf-transform (quantised, instanced, Draco-compressed); embedded buffers; refusals that name
//! what is wrong; files moved as they are.

mod common;

use arps::io::{
    detect_format, read_mesh, read_point_cloud, read_point_cloud_with, transform_file, Format, ReadOptions,
};
use common::{apply, format_fixture, tilted_motion};
use nalgebra::Matrix4;

/// The node matrix trimesh wrote into `fuze_trimesh.glb` (column-major), placing its one mesh.
const FUZE_NODE: [f64; 16] = [
    0.7835715705981133,
    0.18363708214534535,
    -0.5935427666238968,
    0.0,
    -0.058774526721179984,
    0.9729464463247641,
    0.22342955845794912,
    0.0,
    0.6185152777087299,
    -0.14018785484183885,
    0.7731663576460995,
    0.0,
    1.5,
    -2.0,
    0.25,
    1.0,
];

/// `fuze.obj`'s vertices (the mesh the GLB fixtures were made from) placed by `m`.
fn fuze_placed(m: &Matrix4<f64>) -> Vec<[f64; 3]> {
    let obj = read_point_cloud(&format_fixture("fuze.obj"), "fuze.obj").unwrap();
    (0..obj.len()).map(|i| apply(m, obj.point_f64(i))).collect()
}

/// The largest distance from a point of `got` to its nearest in `want`, and from a point of
/// `want` to its nearest in `got` (both ways: every vertex found, none extra).
fn both_ways(got: &[[f64; 3]], want: &[[f64; 3]]) -> f64 {
    let d = |a: &[f64; 3], b: &[f64; 3]| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
    let one = |from: &[[f64; 3]], to: &[[f64; 3]]| {
        from.iter().map(|p| to.iter().map(|q| d(p, q)).fold(f64::INFINITY, f64::min)).fold(0.0, f64::max)
    };
    one(got, want).max(one(want, got))
}

fn points(bytes: &[u8], name: &str) -> Vec<[f64; 3]> {
    let cloud = read_point_cloud(bytes, name).unwrap();
    (0..cloud.len()).map(|i| cloud.point_f64(i)).collect()
}

fn obj_area() -> f64 {
    read_mesh(&format_fixture("fuze.obj"), "fuze.obj").unwrap().surface_area()
}

#[test]
fn a_glb_by_trimesh_is_its_mesh_placed_by_its_node() {
    let bytes = format_fixture("fuze_trimesh.glb");
    assert_eq!(detect_format(&bytes, "").unwrap(), Format::Gltf, "the magic names it");
    let got = points(&bytes, "fuze.glb");
    assert_eq!(got.len(), 664, "trimesh split the OBJ's 502 vertices by texture coordinate");
    let want = fuze_placed(&Matrix4::from_column_slice(&FUZE_NODE));
    assert!(both_ways(&got, &want) < 1e-6, "{}", both_ways(&got, &want));
    let mesh = read_mesh(&bytes, "fuze.glb").unwrap();
    assert_eq!(mesh.triangles.len(), 1000);
    assert!((mesh.surface_area() / obj_area() - 1.0).abs() < 1e-5);
    let options = ReadOptions { surface_points: Some(5000), seed: 3, scan: None, classes: None, min_opacity: None };
    let surface = read_point_cloud_with(&bytes, "fuze.glb", &options).unwrap();
    assert_eq!(surface.len(), 5000);
}

#[test]
fn quantised_positions_are_scaled_back_by_their_node() {
    // gltf-transform quantize: int16 normalised positions, the node's scale undoing it
    let got = points(&format_fixture("fuze_quantized.glb"), "q.glb");
    let want = fuze_placed(&Matrix4::from_column_slice(&FUZE_NODE));
    // 14 bits over the part's 0.22 height: steps of about 1.3e-5
    assert!(both_ways(&got, &want) < 2e-5, "{}", both_ways(&got, &want));
}

#[test]
fn gpu_instances_are_each_placed() {
    // gltf-transform instance: one node drawing the mesh three times (EXT_mesh_gpu_instancing)
    let got = points(&format_fixture("fuze_instanced.glb"), "i.glb");
    assert_eq!(got.len(), 3 * 664);
    for (k, part) in got.chunks(664).enumerate() {
        let angle = 0.5 * k as f64 + 0.2;
        let axis = nalgebra::Unit::new_normalize(nalgebra::Vector3::new(0.1 * k as f64, 1.0, 0.3));
        let m = Matrix4::new_translation(&nalgebra::Vector3::new(0.3 * k as f64, 0.1, -0.2 * k as f64))
            * nalgebra::Rotation3::from_axis_angle(&axis, angle).to_homogeneous();
        assert!(both_ways(part, &fuze_placed(&m)) < 1e-6, "instance {k}");
    }
}

#[test]
fn a_draco_compressed_file_is_refused_by_name() {
    let e = read_point_cloud(&format_fixture("fuze_draco.glb"), "d.glb").unwrap_err().to_string();
    assert!(e.contains("KHR_draco_mesh_compression") && e.contains("glTF"), "{e}");
}

/// A `.gltf` file of the GLB `bytes`: its JSON with the binary chunk as a base64 `data:` URI.
fn embedded(bytes: &[u8]) -> String {
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let mut json: serde_json::Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    let bin = &bytes[28 + json_len..];
    use base64::Engine as _;
    let uri = format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(bin));
    json["buffers"][0]["uri"] = serde_json::Value::String(uri);
    serde_json::to_string_pretty(&json).unwrap()
}

#[test]
fn a_gltf_with_embedded_buffers_reads_as_its_glb() {
    let bytes = format_fixture("fuze_trimesh.glb");
    let text = embedded(&bytes);
    assert_eq!(detect_format(text.as_bytes(), "").unwrap(), Format::Gltf, "sniffed");
    assert_eq!(points(text.as_bytes(), "fuze.gltf"), points(&bytes, "fuze.glb"));
}

/// A GLB file of `json` (a JSON object) and `bin`.
fn glb(json: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut text = serde_json::to_vec(json).unwrap();
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(((28 + text.len() + bin.len()) as u32).to_le_bytes());
    out.extend((text.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(&text);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(&bin);
    out
}

/// A unit square as 4 float positions, drawn by `mode` with `indices` (u16), under nodes that
/// translate by (10, 0, 0) and then scale by 2: a parent and its child.
fn square(mode: u32, indices: &[u16], sparse: bool) -> Vec<u8> {
    let mut bin: Vec<u8> = [[0f32, 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]]
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let index_at = bin.len();
    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let sparse_at = bin.len();
    bin.extend(3u16.to_le_bytes()); // vertex 3 moved to (0, 2, 0)
    bin.extend([0, 0]);
    bin.extend([0f32, 2., 0.].iter().flat_map(|v| v.to_le_bytes()));
    let mut position = serde_json::json!({"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"});
    if sparse {
        position["sparse"] = serde_json::json!({"count": 1, "indices": {"bufferView": 2, "componentType": 5123}, "values": {"bufferView": 2, "byteOffset": 4}});
    }
    let json = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"translation": [10, 0, 0], "children": [1]}, {"scale": [2, 2, 2], "mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": mode}]}],
        "accessors": [position, {"bufferView": 1, "componentType": 5123, "count": indices.len(), "type": "SCALAR"}],
        "bufferViews": [
            {"buffer": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": index_at, "byteLength": 2 * indices.len()},
            {"buffer": 0, "byteOffset": sparse_at, "byteLength": 16}
        ],
        "buffers": [{"byteLength": bin.len()}]
    });
    glb(&json, &bin)
}

#[test]
fn nodes_compose_and_strips_and_fans_are_triangulated() {
    let list = read_mesh(&square(4, &[0, 1, 2, 0, 2, 3], false), "s.glb").unwrap();
    assert_eq!(list.vertices, vec![[10., 0., 0.], [12., 0., 0.], [12., 2., 0.], [10., 2., 0.]], "parent * child");
    assert_eq!(list.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    let strip = read_mesh(&square(5, &[0, 1, 3, 2], false), "s.glb").unwrap();
    assert_eq!(strip.triangles, vec![[0, 1, 3], [1, 2, 3]]);
    let fan = read_mesh(&square(6, &[0, 1, 2, 3], false), "s.glb").unwrap();
    assert_eq!(fan.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    for m in [&list, &strip, &fan] {
        assert!((m.surface_area() - 4.0).abs() < 1e-9);
    }
    let sparse = read_mesh(&square(4, &[0, 1, 2, 0, 2, 3], true), "s.glb").unwrap();
    assert_eq!(sparse.vertices[3], [10., 4., 0.], "the sparse value replaced vertex 3");
}

#[test]
fn broken_files_are_refused_with_what_is_wrong() {
    let good = square(4, &[0, 1, 2, 0, 2, 3], false);
    let cases: Vec<(Vec<u8>, &str)> = vec![
        (good[..good.len() - 8].to_vec(), "truncated"),
        (square(4, &[0, 1, 2, 0, 2, 9], false), "vertex index 9 is out of range (4 vertices)"),
        (b"glTF\x01\0\0\0\x14\0\0\0\0\0\0\0JSON".to_vec(), "version 1"),
        (b"{\"asset\": {\"version\": \"2.0\"}, \"buffers\": [{\"uri\": \"scene.bin\", \"byteLength\": 4}]}".to_vec(), "'scene.bin'"),
        (b"{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [{\"children\": [1]}, {\"children\": [0]}], \"scenes\": [{\"nodes\": [0]}]}".to_vec(), "cycle"),
        (b"{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [{\"mesh\": 3}]}".to_vec(), "meshes[3]"),
        (b"{\"asset\": {\"version\": \"2.0\"".to_vec(), "malformed"),
    ];
    for (bytes, want) in cases {
        let e = read_mesh(&bytes, "x.gltf").map(|_| ()).unwrap_err().to_string();
        assert!(e.contains(want) && e.contains("glTF"), "want '{want}' in: {e}");
    }
    let mut past_view = serde_json::from_slice::<serde_json::Value>(
        &good[20..20 + u32::from_le_bytes(good[12..16].try_into().unwrap()) as usize],
    )
    .unwrap();
    past_view["accessors"][0]["count"] = serde_json::json!(5);
    let e = read_point_cloud(&glb(&past_view, &good[good.len() - 64..]), "p.glb").unwrap_err().to_string();
    assert!(e.contains("accessors[0]"), "{e}");
    // a stride of 2^63 wrapped the size check's product to 0, and the read then panicked
    let mut wrapping = past_view.clone();
    wrapping["accessors"][0]["count"] = serde_json::json!(3);
    wrapping["bufferViews"][0]["byteStride"] = serde_json::json!(1u64 << 63);
    let e = read_point_cloud(&glb(&wrapping, &good[good.len() - 64..]), "p.glb").unwrap_err().to_string();
    assert!(e.contains("accessors[0]") && e.contains("need"), "{e}");
}

/// Equal but for the cloud's `f32` storage (a cloud near zero keeps its points in `f32`).
fn close(got: &[f64; 3], want: &[f64; 3]) -> bool {
    let scale = (want[0] * want[0] + want[1] * want[1] + want[2] * want[2]).sqrt().max(1.0);
    (0..3).all(|k| (got[k] - want[k]).abs() <= 4e-7 * scale)
}

#[test]
fn a_glb_moves_as_it_is_under_a_new_root() {
    let m = tilted_motion();
    for name in ["fuze_trimesh.glb", "fuze_quantized.glb", "fuze_instanced.glb"] {
        let bytes = format_fixture(name);
        let moved = transform_file(&bytes, name, &m).unwrap();
        let (before, after) = (points(&bytes, name), points(&moved, name));
        assert_eq!(before.len(), after.len());
        for (p, q) in before.iter().zip(&after) {
            let want = apply(&m, *p);
            assert!(close(q, &want), "{name}: {q:?} vs {want:?}");
        }
        assert_eq!(&moved[moved.len() - 64..], &bytes[bytes.len() - 64..], "{name}: the binary chunk kept");
    }
    let text = embedded(&format_fixture("fuze_trimesh.glb"));
    let moved = transform_file(text.as_bytes(), "f.gltf", &m).unwrap();
    let (before, after) = (points(text.as_bytes(), "f.gltf"), points(&moved, "f.gltf"));
    assert!(before.iter().zip(&after).all(|(p, q)| close(q, &apply(&m, *p))));
    let mirror = Matrix4::new_nonuniform_scaling(&nalgebra::Vector3::new(-1.0, 1.0, 1.0));
    assert!(transform_file(&format_fixture("fuze_trimesh.glb"), "f.glb", &mirror).is_err());
}

#[test]
fn a_file_without_scenes_moves_its_top_nodes() {
    // no scenes: the top nodes' own transforms take the motion, as a matrix or as TRS
    let bytes = square(4, &[0, 1, 2, 0, 2, 3], false);
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let mut json: serde_json::Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    let bin = bytes[28 + json_len..].to_vec();
    json.as_object_mut().unwrap().remove("scenes");
    json.as_object_mut().unwrap().remove("scene");
    let m = tilted_motion() * Matrix4::new_scaling(1000.0);
    for with_matrix in [false, true] {
        if with_matrix {
            json["nodes"][0] =
                serde_json::json!({"matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 10, 0, 0, 1], "children": [1]});
        }
        let file = glb(&json, &bin);
        let moved = transform_file(&file, "s.glb", &m).unwrap();
        let (before, after) = (points(&file, "s.glb"), points(&moved, "s.glb"));
        for (p, q) in before.iter().zip(&after) {
            let want = apply(&m, *p);
            assert!(close(q, &want), "{q:?} vs {want:?}");
        }
    }
}

/// A unit square (4 float positions, two triangles) whose mesh node is moved by (100, 0, 0), with
/// `extra` merged into the mesh's primitive, node and file (JSON objects) and `more` appended to
/// the binary chunk after the square's 48 + 12 bytes.
fn square_with(prim: serde_json::Value, node: serde_json::Value, file: serde_json::Value, more: &[u8]) -> Vec<u8> {
    let mut bin: Vec<u8> = [[0f32, 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]]
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    bin.extend([0u16, 1, 2, 0, 2, 3].iter().flat_map(|i| i.to_le_bytes()));
    bin.extend(more);
    let mut p = serde_json::json!({"attributes": {"POSITION": 0}, "indices": 1});
    p.as_object_mut().unwrap().extend(prim.as_object().unwrap().clone());
    let mut n = serde_json::json!({"mesh": 0, "translation": [100, 0, 0]});
    n.as_object_mut().unwrap().extend(node.as_object().unwrap().clone());
    let mut json = serde_json::json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [n],
        "meshes": [{"primitives": [p]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}
        ],
        "bufferViews": [{"buffer": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 12}],
        "buffers": [{"byteLength": 60 + more.len()}]
    });
    for (k, v) in file.as_object().unwrap() {
        match json[k.as_str()].as_array_mut() {
            Some(list) => list.extend(v.as_array().unwrap().iter().cloned()),
            None => json[k.as_str()] = v.clone(),
        }
    }
    glb(&json, &bin)
}

#[test]
fn morph_targets_take_their_default_weights() {
    // a target that lifts vertex 2 by 1, at the mesh's weight 0.5 (the node's 0.25 wins when set)
    let lift: Vec<u8> = [[0f32, 0., 0.], [0., 0., 0.], [0., 0., 1.], [0., 0., 0.]]
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let file = || {
        serde_json::json!({
            "accessors": [{"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC3"}],
            "bufferViews": [{"buffer": 0, "byteOffset": 60, "byteLength": 48}]
        })
    };
    let targets = serde_json::json!({"targets": [{"POSITION": 2}]});
    let mut bytes = square_with(targets.clone(), serde_json::json!({}), file(), &lift);
    let m = read_mesh(&bytes, "m.glb").unwrap();
    assert_eq!(m.vertices[2], [101., 1., 0.], "no weights: the base mesh");
    let with_weights = |node: serde_json::Value, mesh_weights: f64| {
        let b = square_with(targets.clone(), node, file(), &lift);
        let len = u32::from_le_bytes(b[12..16].try_into().unwrap()) as usize;
        let mut json: serde_json::Value = serde_json::from_slice(&b[20..20 + len]).unwrap();
        json["meshes"][0]["weights"] = serde_json::json!([mesh_weights]);
        glb(&json, &b[28 + len..])
    };
    bytes = with_weights(serde_json::json!({}), 0.5);
    assert_eq!(read_mesh(&bytes, "m.glb").unwrap().vertices[2], [101., 1., 0.5], "the mesh's weight");
    bytes = with_weights(serde_json::json!({"weights": [0.25]}), 0.5);
    assert_eq!(read_mesh(&bytes, "m.glb").unwrap().vertices[2], [101., 1., 0.25], "the node's weight");
}

#[test]
fn skinned_meshes_are_posed_by_their_joints_not_their_node() {
    // two joints: one moved by (5, 0, 0), one turned a quarter about z at (0, 1, 0); vertices 0
    // and 1 follow the first, 2 the second, 3 half of each; the mesh node's (100, 0, 0) ignored
    let mut more: Vec<u8> =
        [[0u8, 0, 0, 0], [0, 0, 0, 0], [1, 0, 0, 0], [0, 1, 0, 0]].iter().flatten().copied().collect();
    more.extend(
        [[1f32, 0., 0., 0.], [1., 0., 0., 0.], [1., 0., 0., 0.], [0.5, 0.5, 0., 0.]]
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes()),
    );
    // the second joint's inverse bind matrix: its bind pose at (0, 1, 0)
    let ibm: [f32; 16] = [1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., 0., 0., -1., 0., 1.];
    more.extend(Matrix4::<f32>::identity().as_slice().iter().chain(&ibm).flat_map(|v| v.to_le_bytes()));
    let file = serde_json::json!({
        "accessors": [
            {"bufferView": 2, "componentType": 5121, "count": 4, "type": "VEC4"},
            {"bufferView": 3, "componentType": 5126, "count": 4, "type": "VEC4"},
            {"bufferView": 4, "componentType": 5126, "count": 2, "type": "MAT4"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 60, "byteLength": 16},
            {"buffer": 0, "byteOffset": 76, "byteLength": 64},
            {"buffer": 0, "byteOffset": 140, "byteLength": 128}
        ],
        "nodes": [
            {"translation": [5, 0, 0]},
            {"translation": [0, 1, 0], "rotation": [0, 0, std::f64::consts::FRAC_1_SQRT_2, std::f64::consts::FRAC_1_SQRT_2]}
        ],
        "skins": [{"joints": [1, 2], "inverseBindMatrices": 4}]
    });
    let prim = serde_json::json!({"attributes": {"POSITION": 0, "JOINTS_0": 2, "WEIGHTS_0": 3}});
    let bytes = square_with(prim, serde_json::json!({"skin": 0}), file, &more);
    let m = read_mesh(&bytes, "s.glb").unwrap();
    let near = |a: [f32; 3], b: [f32; 3]| (0..3).all(|k| (a[k] - b[k]).abs() < 1e-6);
    assert!(near(m.vertices[0], [5., 0., 0.]) && near(m.vertices[1], [6., 0., 0.]), "{:?}", m.vertices);
    // (1, 1, 0) is (1, 0, 0) from the second joint's bind pose: turned a quarter, (0, 1, 0) from it
    assert!(near(m.vertices[2], [0., 2., 0.]), "{:?}", m.vertices);
    // (0, 1, 0): the first joint puts it at (5, 1, 0), the second leaves it at (0, 1, 0)
    assert!(near(m.vertices[3], [2.5, 1., 0.]), "{:?}", m.vertices);
}

#[test]
fn draco_used_but_not_required_reads_the_uncompressed_data() {
    let draco = serde_json::json!({"extensions": {"KHR_draco_mesh_compression": {"bufferView": 0, "attributes": {"POSITION": 0}}}});
    let used = serde_json::json!({"extensionsUsed": ["KHR_draco_mesh_compression"]});
    let m = read_mesh(&square_with(draco, serde_json::json!({}), used, &[]), "d.glb").unwrap();
    assert_eq!(m.vertices.len(), 4);
    assert_eq!(m.vertices[2], [101., 1., 0.]);
}

#[test]
fn a_default_scene_without_meshes_says_so() {
    let other = serde_json::json!({"scene": 1, "scenes": [{"nodes": []}]});
    let e = read_mesh(&square_with(serde_json::json!({}), serde_json::json!({}), other, &[]), "e.glb")
        .unwrap_err()
        .to_string();
    assert!(e.contains("default scene draws none of its 1 meshes"), "{e}");
}
