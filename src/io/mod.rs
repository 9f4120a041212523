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

impl Mesh {
    /// Total surface area.
    pub fn surface_area(&self) -> f64 {
        self.triangle_areas().iter().sum()
    }

    fn triangle_areas(&self) -> Vec<f64> {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| {
                    self.vertices
                        .get(i as usize)
                        .copied()
                        .unwrap_or([0.0; 3])
                        .map(|v| v as f64)
                });
                let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
                let cr = [
                    u[1] * v[2] - u[2] * v[1],
                    u[2] * v[0] - u[0] * v[2],
                    u[0] * v[1] - u[1] * v[0],
                ];
                let area = 0.5 * (cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]).sqrt();
                if area.is_finite() {
                    area
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// `n` points uniformly distributed over the surface (area-weighted triangle choice, uniform
    /// barycentric coordinates), deterministic for a seed. Fails if no triangle has positive area
    /// or a triangle index is out of range.
    pub fn sample_surface(&self, n: usize, seed: u64) -> Result<PointCloud> {
        use rand::Rng;
        if let Some(t) = self
            .triangles
            .iter()
            .find(|t| t.iter().any(|&i| i as usize >= self.vertices.len()))
        {
            return Err(crate::Error::InvalidCloud(format!(
                "mesh triangle {t:?} refers to a vertex beyond the {} vertices",
                self.vertices.len()
            )));
        }
        let areas = self.triangle_areas();
        let mut cumulative = Vec::with_capacity(areas.len());
        let mut total = 0.0;
        for a in &areas {
            total += a;
            cumulative.push(total);
        }
        if !(total > 0.0) {
            return Err(crate::Error::InvalidCloud(
                "mesh has no triangle with positive area to sample".into(),
            ));
        }
        let mut rng = crate::sampling::rng(seed);
        let mut points = Vec::with_capacity(n);
        for _ in 0..n {
            let r = rng.random::<f64>() * total;
            let k = cumulative.partition_point(|&c| c <= r).min(areas.len() - 1);
            let [a, b, c] = self.triangles[k].map(|i| self.vertices[i as usize].map(|v| v as f64));
            let (mut u, mut v) = (rng.random::<f64>(), rng.random::<f64>());
            if u + v > 1.0 {
                u = 1.0 - u;
                v = 1.0 - v;
            }
            points.push(
                [0, 1, 2].map(|ax| (a[ax] + u * (b[ax] - a[ax]) + v * (c[ax] - a[ax])) as f32),
            );
        }
        Ok(PointCloud::new(points))
    }
}

/// Reads a triangle mesh (OBJ, OFF, STL, PLY with faces) from a file's bytes.
pub fn read_mesh(bytes: &[u8], file_name: &str) -> Result<Mesh> {
    let _ = (bytes, file_name);
    todo!("helper: io")
}
