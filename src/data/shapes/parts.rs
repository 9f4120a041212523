//! Parametric parts: boxes, frusta (cylinders and cones), ellipsoids, tori, lathe (revolved)
//! profiles, extruded polygons and rods, plus the affine placement of a part and a seeded
//! random helper. Every part is a closed triangle mesh in its own local frame (z up) unless said
//! otherwise; categories assemble them with [`Shape::add`].

use crate::io::Mesh;
use nalgebra::{Matrix3, Matrix4, Rotation3, Vector3};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use std::f64::consts::{PI, TAU};

/// A shape under construction: the union (as a triangle soup) of placed parts.
#[derive(Default)]
pub struct Shape {
    /// The accumulated mesh.
    pub mesh: Mesh,
}

impl Shape {
    /// Adds a part, mapped by `xf` (any affine 4x4).
    pub fn add(&mut self, part: Mesh, xf: &Matrix4<f64>) {
        let base = self.mesh.vertices.len() as u32;
        self.mesh.vertices.extend(part.vertices.iter().map(|&v| {
            let p = xf * nalgebra::Vector4::new(v[0] as f64, v[1] as f64, v[2] as f64, 1.0);
            [p.x as f32, p.y as f32, p.z as f32]
        }));
        self.mesh.triangles.extend(part.triangles.iter().map(|t| t.map(|i| i + base)));
    }

    /// Adds a part translated to `at`.
    pub fn add_at(&mut self, part: Mesh, at: [f64; 3]) {
        self.add(part, &translate(at));
    }
}

/// Translation by `t`.
pub fn translate(t: [f64; 3]) -> Matrix4<f64> {
    Matrix4::new_translation(&Vector3::from(t))
}

/// Rotation about an axis (`0` = x, `1` = y, `2` = z) by `angle` radians.
pub fn rotate(axis: usize, angle: f64) -> Matrix4<f64> {
    let a = [Vector3::x_axis(), Vector3::y_axis(), Vector3::z_axis()][axis];
    Rotation3::from_axis_angle(&a, angle).to_homogeneous()
}

/// Translation after rotation: `translate(t) * rotate(axis, angle)`.
pub fn place(t: [f64; 3], axis: usize, angle: f64) -> Matrix4<f64> {
    translate(t) * rotate(axis, angle)
}

/// A random helper on the crate's seeded generator.
pub struct Dice(pub ChaCha8Rng);

impl Dice {
    /// Seeded.
    pub fn new(seed: u64) -> Self {
        Self(crate::sampling::rng(seed))
    }
    /// Uniform in `[a, b)`.
    pub fn u(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.0.random::<f64>()
    }
    /// Uniform integer in `a..=b`.
    pub fn int(&mut self, a: usize, b: usize) -> usize {
        self.0.random_range(a..=b)
    }
    /// True with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        self.0.random::<f64>() < p
    }
    /// `+1` or `-1`.
    pub fn sign(&mut self) -> f64 {
        if self.chance(0.5) {
            1.0
        } else {
            -1.0
        }
    }
    /// One of `items`.
    pub fn pick<T: Copy>(&mut self, items: &[T]) -> T {
        items[self.0.random_range(0..items.len())]
    }
}

fn v(p: [f64; 3]) -> [f32; 3] {
    p.map(|x| x as f32)
}

/// An axis-aligned box of size `s`, centred at the origin.
pub fn cuboid(s: [f64; 3]) -> Mesh {
    let h = s.map(|x| x * 0.5);
    let mut vertices = Vec::with_capacity(8);
    for i in 0..8 {
        vertices.push(v([
            if i & 1 == 0 { -h[0] } else { h[0] },
            if i & 2 == 0 { -h[1] } else { h[1] },
            if i & 4 == 0 { -h[2] } else { h[2] },
        ]));
    }
    let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let mut triangles = Vec::with_capacity(12);
    for q in quads {
        triangles.push([q[0], q[1], q[2]]);
        triangles.push([q[0], q[2], q[3]]);
    }
    Mesh { vertices, triangles }
}

/// A box of size `s` whose bottom face centre is at the origin (sits on z = 0).
pub fn slab(s: [f64; 3]) -> Mesh {
    let mut m = cuboid(s);
    for p in &mut m.vertices {
        p[2] += (s[2] * 0.5) as f32;
    }
    m
}

/// Revolves a profile of `(radius, z)` points about the z axis with `segments` sides. Radii of 0
/// close the surface at that end (a pole); otherwise `cap_ends` adds flat discs at the first and
/// last profile points. The profile may go up and back down (a wall with thickness).
pub fn lathe(profile: &[(f64, f64)], segments: usize, cap_ends: bool) -> Mesh {
    let segments = segments.max(3);
    let mut m = Mesh::default();
    let rings = profile.len();
    for &(r, z) in profile {
        for k in 0..segments {
            let a = TAU * k as f64 / segments as f64;
            m.vertices.push(v([r * a.cos(), r * a.sin(), z]));
        }
    }
    let idx = |ring: usize, k: usize| (ring * segments + k % segments) as u32;
    for i in 0..rings.saturating_sub(1) {
        for k in 0..segments {
            let (a, b, c, d) = (idx(i, k), idx(i, k + 1), idx(i + 1, k + 1), idx(i + 1, k));
            m.triangles.push([a, b, c]);
            m.triangles.push([a, c, d]);
        }
    }
    if cap_ends && rings >= 2 {
        for (ring, flip) in [(0, true), (rings - 1, false)] {
            let (r, z) = profile[ring];
            if r <= 0.0 {
                continue;
            }
            let c = m.vertices.len() as u32;
            m.vertices.push(v([0.0, 0.0, z]));
            for k in 0..segments {
                let (a, b) = (idx(ring, k), idx(ring, k + 1));
                m.triangles.push(if flip { [c, b, a] } else { [c, a, b] });
            }
        }
    }
    m
}

/// A closed frustum along z from `z = 0` (radius `r0`) to `z = h` (radius `r1`); a cylinder when
/// the radii are equal, a cone when `r1 = 0`.
pub fn frustum(r0: f64, r1: f64, h: f64, segments: usize) -> Mesh {
    lathe(&[(0.0, 0.0), (r0, 0.0), (r1, h), (0.0, h)], segments, false)
}

/// A closed cylinder along z from `z = 0` to `z = h`.
pub fn cylinder(r: f64, h: f64, segments: usize) -> Mesh {
    frustum(r, r, h, segments)
}

/// An ellipsoid with semi-axes `radii`, centred at the origin.
pub fn ellipsoid(radii: [f64; 3], segments: usize) -> Mesh {
    let rings = (segments / 2).max(3);
    let profile: Vec<(f64, f64)> = (0..=rings)
        .map(|i| {
            let t = PI * i as f64 / rings as f64;
            (t.sin(), -t.cos())
        })
        .collect();
    let mut m = lathe(&profile, segments, false);
    for p in &mut m.vertices {
        for a in 0..3 {
            p[a] *= radii[a] as f32;
        }
    }
    m
}

/// A (possibly partial) torus in the xy plane: ring radius `big`, tube radius `small`, swept over
/// `arc` radians from the +x axis. Partial tori are capped at both ends.
pub fn torus(big: f64, small: f64, arc: f64, segments: usize, tube: usize) -> Mesh {
    let full = arc >= TAU - 1e-9;
    let steps = segments.max(3);
    let rings = if full { steps } else { steps + 1 };
    let mut m = Mesh::default();
    for i in 0..rings {
        let a = arc * i as f64 / steps as f64;
        let (s, c) = a.sin_cos();
        for k in 0..tube {
            let b = TAU * k as f64 / tube as f64;
            let r = big + small * b.cos();
            m.vertices.push(v([r * c, r * s, small * b.sin()]));
        }
    }
    let idx = |i: usize, k: usize| ((i % rings) * tube + k % tube) as u32;
    for i in 0..steps {
        for k in 0..tube {
            let (a, b, c, d) = (idx(i, k), idx(i + 1, k), idx(i + 1, k + 1), idx(i, k + 1));
            m.triangles.push([a, b, c]);
            m.triangles.push([a, c, d]);
        }
    }
    if !full {
        for (ring, flip) in [(0, false), (rings - 1, true)] {
            let a = arc * ring as f64 / steps as f64;
            let c = m.vertices.len() as u32;
            m.vertices.push(v([big * a.cos(), big * a.sin(), 0.0]));
            for k in 0..tube {
                let (p, q) = (idx(ring, k), idx(ring, k + 1));
                m.triangles.push(if flip { [c, q, p] } else { [c, p, q] });
            }
        }
    }
    m
}

/// Ear-clipping triangulation of a simple polygon (either orientation); returns index triples.
pub fn triangulate(poly: &[[f64; 2]]) -> Vec<[usize; 3]> {
    let n = poly.len();
    if n < 3 {
        return Vec::new();
    }
    let area2: f64 = (0..n)
        .map(|i| {
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum();
    let orient = if area2 >= 0.0 { 1.0 } else { -1.0 };
    let cross = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])) * orient
    };
    let inside = |p: [f64; 2], a, b, c| cross(a, b, p) > 0.0 && cross(b, c, p) > 0.0 && cross(c, a, p) > 0.0;
    let mut idx: Vec<usize> = (0..n).collect();
    let mut out = Vec::with_capacity(n - 2);
    let mut guard = 0;
    while idx.len() > 3 && guard < n * n {
        guard += 1;
        let m = idx.len();
        let mut clipped = false;
        for i in 0..m {
            let (ia, ib, ic) = (idx[(i + m - 1) % m], idx[i], idx[(i + 1) % m]);
            let (a, b, c) = (poly[ia], poly[ib], poly[ic]);
            if cross(a, b, c) <= 1e-12 {
                continue;
            }
            if idx.iter().any(|&j| j != ia && j != ib && j != ic && inside(poly[j], a, b, c)) {
                continue;
            }
            out.push([ia, ib, ic]);
            idx.remove(i);
            clipped = true;
            break;
        }
        if !clipped {
            // degenerate remainder: fan it
            for k in 1..idx.len() - 1 {
                out.push([idx[0], idx[k], idx[k + 1]]);
            }
            return out;
        }
    }
    if idx.len() == 3 {
        out.push([idx[0], idx[1], idx[2]]);
    }
    out
}

/// A prism: the simple polygon `outline` (in the xy plane) extruded along z from 0 to `depth`.
pub fn extrude(outline: &[[f64; 2]], depth: f64) -> Mesh {
    let n = outline.len();
    let mut m = Mesh::default();
    for z in [0.0, depth] {
        for p in outline {
            m.vertices.push(v([p[0], p[1], z]));
        }
    }
    for t in triangulate(outline) {
        let t = t.map(|i| i as u32);
        m.triangles.push([t[0], t[2], t[1]]);
        m.triangles.push([t[0] + n as u32, t[1] + n as u32, t[2] + n as u32]);
    }
    for i in 0..n {
        let j = (i + 1) % n;
        let (a, b, c, d) = (i as u32, j as u32, (j + n) as u32, (i + n) as u32);
        m.triangles.push([a, b, c]);
        m.triangles.push([a, c, d]);
    }
    m
}

/// A closed cylinder of radius `r` from point `a` to point `b`.
pub fn rod(a: [f64; 3], b: [f64; 3], r: f64, segments: usize) -> Mesh {
    let (pa, pb) = (Vector3::from(a), Vector3::from(b));
    let d = pb - pa;
    let len = d.norm().max(1e-9);
    let rot = Rotation3::rotation_between(&Vector3::z(), &(d / len))
        .unwrap_or_else(|| Rotation3::from_axis_angle(&Vector3::x_axis(), PI));
    let xf = Matrix4::new_translation(&pa) * rot.to_homogeneous();
    let mut s = Shape::default();
    s.add(cylinder(r, len, segments), &xf);
    s.mesh
}

/// A rectangular beam of cross-section `w` x `w` from `a` to `b`.
pub fn beam(a: [f64; 3], b: [f64; 3], w: f64) -> Mesh {
    let (pa, pb) = (Vector3::from(a), Vector3::from(b));
    let d = pb - pa;
    let len = d.norm().max(1e-9);
    let rot = Rotation3::rotation_between(&Vector3::z(), &(d / len))
        .unwrap_or_else(|| Rotation3::from_axis_angle(&Vector3::x_axis(), PI));
    let xf = Matrix4::new_translation(&pa) * rot.to_homogeneous();
    let mut s = Shape::default();
    s.add(slab([w, w, len]), &xf);
    s.mesh
}

/// A thin-walled open-top box shell (floor and four walls) of outer size `s` and wall `t`,
/// sitting on z = 0: bathtubs, display cases, drawers.
pub fn open_box(s: [f64; 3], t: f64) -> Mesh {
    let mut sh = Shape::default();
    sh.add_at(slab([s[0], s[1], t]), [0.0, 0.0, 0.0]);
    let h = s[2] - t;
    for sx in [-1.0, 1.0] {
        sh.add_at(slab([t, s[1], h]), [sx * (s[0] - t) * 0.5, 0.0, t]);
    }
    for sy in [-1.0, 1.0] {
        sh.add_at(slab([s[0] - 2.0 * t, t, h]), [0.0, sy * (s[1] - t) * 0.5, t]);
    }
    sh.mesh
}

/// Applies a general 3x3 linear map (shear, non-uniform scale) to a part.
pub fn linear(m: Mesh, a: &Matrix3<f64>) -> Mesh {
    let mut s = Shape::default();
    s.add(m, &a.to_homogeneous());
    s.mesh
}

/// A smooth closed outline sampled from a radius function of the angle: `r(theta)` in the xy plane.
pub fn polar_outline(n: usize, r: impl Fn(f64) -> [f64; 2]) -> Vec<[f64; 2]> {
    (0..n).map(|i| r(TAU * i as f64 / n as f64)).collect()
}
