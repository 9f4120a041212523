//! Mesh area and area-weighted uniform surface sampling.

use super::Mesh;
use crate::cloud::PointCloud;
use crate::{Error, Result};
use rand::Rng;

/// The corners of triangle `t` of `vertices`, or `None` when an index is out of range.
fn corners(vertices: &[[f64; 3]], t: &[u32; 3]) -> Option<[[f64; 3]; 3]> {
    let mut c = [[0.0f64; 3]; 3];
    for (k, &i) in t.iter().enumerate() {
        c[k] = *vertices.get(i as usize)?;
    }
    Some(c)
}

fn area_of(c: &[[f64; 3]; 3]) -> f64 {
    let e1 = [0, 1, 2].map(|a| c[1][a] - c[0][a]);
    let e2 = [0, 1, 2].map(|a| c[2][a] - c[0][a]);
    let x = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
    0.5 * (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt()
}

/// Draws `n` points uniformly over the surface of the triangles `triangles` of `vertices`: a
/// triangle is chosen with probability proportional to its area (binary search in a cumulative
/// area table), then a point uniformly inside it (`A + s(1-r2)(B-A) + s r2 (C-A)` with
/// `s = sqrt(r1)`), all in `f64`. The same seed gives the same points on every platform.
///
/// Fails when a triangle has an out-of-range vertex index, or when no triangle has a positive,
/// finite area.
pub(crate) fn sample_triangles(
    vertices: &[[f64; 3]],
    triangles: &[[u32; 3]],
    n: usize,
    seed: u64,
) -> Result<Vec<[f64; 3]>> {
    // the triangles of positive area (their indices, 4 bytes each, not their corners: a 1 GiB STL
    // holds 21 million) and the running sum of their areas
    let mut cumulative = Vec::with_capacity(triangles.len());
    let mut chosen: Vec<u32> = Vec::with_capacity(triangles.len());
    let mut total = 0.0f64;
    for (ti, t) in triangles.iter().enumerate() {
        let c = corners(vertices, t).ok_or_else(|| {
            Error::InvalidCloud(format!(
                "mesh triangle {ti} has a vertex index out of range ({t:?}, {} vertices)",
                vertices.len()
            ))
        })?;
        let a = area_of(&c);
        if a > 0.0 && a.is_finite() && (total + a).is_finite() {
            total += a;
            cumulative.push(total);
            chosen.push(ti as u32);
        }
    }
    if chosen.is_empty() {
        return Err(Error::InvalidCloud(format!(
            "cannot sample the mesh surface: none of its {} triangles has a positive, finite area",
            triangles.len()
        )));
    }
    let mut rng = crate::sampling::rng(seed);
    let mut points = Vec::with_capacity(n.min(1 << 20));
    for _ in 0..n {
        let u = rng.random::<f64>() * total;
        let k = cumulative.partition_point(|&c| c <= u).min(chosen.len() - 1);
        // checked above: every index is in range
        let Some([a, b, c]) = corners(vertices, &triangles[chosen[k] as usize]) else { continue };
        let s = rng.random::<f64>().sqrt();
        let r2 = rng.random::<f64>();
        let (wb, wc) = (s * (1.0 - r2), s * r2);
        points.push([0, 1, 2].map(|i| a[i] + wb * (b[i] - a[i]) + wc * (c[i] - a[i])));
    }
    Ok(points)
}

impl Mesh {
    /// Total surface area (in `f64`). Triangles with an out-of-range index or a non-finite
    /// area (NaN / infinite vertices) contribute nothing.
    pub fn surface_area(&self) -> f64 {
        let vertices: Vec<[f64; 3]> = self.vertices.iter().map(|v| v.map(|x| x as f64)).collect();
        self.triangles
            .iter()
            .filter_map(|t| corners(&vertices, t))
            .map(|c| area_of(&c))
            .filter(|a| a.is_finite())
            .fold(0.0, |s, a| s + a)
    }

    /// Draws `n` points uniformly over the surface: a triangle is chosen with probability
    /// proportional to its area (binary search in a cumulative area table), then a point
    /// uniformly inside it (`A + s(1-r2)(B-A) + s r2 (C-A)` with `s = sqrt(r1)`), in `f64`. The
    /// same seed gives the same points on every platform.
    ///
    /// Fails when a triangle has an out-of-range vertex index, or when no triangle has a
    /// positive, finite area.
    pub fn sample_surface(&self, n: usize, seed: u64) -> Result<PointCloud> {
        let vertices: Vec<[f64; 3]> = self.vertices.iter().map(|v| v.map(|x| x as f64)).collect();
        let points = sample_triangles(&vertices, &self.triangles, n, seed)?;
        Ok(PointCloud::new(points.into_iter().map(|p| p.map(|x| x as f32)).collect()))
    }
}
