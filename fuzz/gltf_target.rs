// Shared by the `read_gltf` fuzz target and `tests/io_fuzz_regressions.rs` (which replays its
// inputs), through `include!`, so both check a glTF file the same way.

/// The `read_gltf` target's body: the bytes as a `.gltf` file when they start with `{`, else as
/// a `.glb`. A mesh that reads has in-range indices, and the file moved by a fixed rigid motion
/// reads again, to as many vertices and triangles. `Ok(triangles)` or the reader's error.
fn gltf_target(data: &[u8]) -> Result<usize, String> {
    let name = if data.first() == Some(&b'{') { "a.gltf" } else { "a.glb" };
    let mesh = arps::io::read_mesh(data, name).map_err(|e| e.to_string())?;
    let n = mesh.vertices.len();
    assert!(mesh.triangles.iter().flatten().all(|&i| (i as usize) < n));
    let motion = nalgebra::Matrix4::new_translation(&nalgebra::Vector3::new(0.5, -2.0, 3.0))
        * nalgebra::Rotation3::from_euler_angles(0.3, -0.2, 1.1).to_homogeneous();
    if let Ok(moved) = arps::io::transform_file(data, name, &motion) {
        let again = arps::io::read_mesh(&moved, name).expect("a moved file reads");
        assert_eq!((again.vertices.len(), again.triangles.len()), (n, mesh.triangles.len()));
    }
    Ok(mesh.triangles.len())
}
