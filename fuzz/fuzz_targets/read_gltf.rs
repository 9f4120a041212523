//! glTF: the bytes as a `.gltf` file when they start with `{`, else as a `.glb`. A mesh that
//! reads has in-range indices, and the file moved by a fixed rigid motion reads again, to as many
//! vertices and triangles.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let name = if data.first() == Some(&b'{') { "a.gltf" } else { "a.glb" };
    let Ok(mesh) = arps::io::read_mesh(data, name) else { return };
    let n = mesh.vertices.len();
    assert!(mesh.triangles.iter().flatten().all(|&i| (i as usize) < n));
    let motion = nalgebra::Matrix4::new_translation(&nalgebra::Vector3::new(0.5, -2.0, 3.0))
        * nalgebra::Rotation3::from_euler_angles(0.3, -0.2, 1.1).to_homogeneous();
    if let Ok(moved) = arps::io::transform_file(data, name, &motion) {
        let again = arps::io::read_mesh(&moved, name).expect("a moved file reads");
        assert_eq!((again.vertices.len(), again.triangles.len()), (n, mesh.triangles.len()));
    }
});
