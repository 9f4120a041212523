//! Readers for point-cloud and mesh files, and a binary PLY writer.

use crate::cloud::PointCloud;
use crate::Result;

/// A triangle mesh (vertices and triangles), as read from OBJ/OFF/STL/PLY.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub vertices: Vec<[f32; 3]>,
    /// Triangles as vertex indices (polygons are fan-triangulated).
    pub triangles: Vec<[u32; 3]>,
}

/// Reads a point cloud from a file's bytes; the format comes from the file name's extension,
/// else it is sniffed from the content. Mesh formats give their vertices.
pub fn read_point_cloud(bytes: &[u8], file_name: &str) -> Result<PointCloud> {
    let _ = (bytes, file_name);
    todo!("helper: io")
}

/// Reads a point cloud from a path (the file name picks the format).
#[cfg(not(target_arch = "wasm32"))]
pub fn read_path(path: &std::path::Path) -> Result<PointCloud> {
    let bytes = std::fs::read(path)?;
    read_point_cloud(
        &bytes,
        &path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
    )
}

/// Binary little-endian PLY with float x, y, z.
pub fn write_ply_binary(cloud: &PointCloud) -> Vec<u8> {
    let _ = cloud;
    todo!("helper: io")
}
