//! Tiny procedural pairs for tests and benchmarks (not the training data pipeline): sphere,
//! box-surface and cylinder clouds, a half-space crop per cloud, a random rigid motion within
//! +-45 degrees per axis and up to 0.5 translation, and small noise.

use super::pair::Pair;
use crate::sampling::rng;
use crate::transform::{euler_xyz, from_rotation_translation, mapping};
use nalgebra::Vector3;
use rand::Rng;

/// The shapes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// Unit sphere surface.
    Sphere,
    /// Surface of a 2 x 1.2 x 0.8 box.
    Box,
    /// Cylinder (radius 0.5, height 2) with caps.
    Cylinder,
}

fn sample(shape: Shape, n: usize, r: &mut impl Rng) -> Vec<[f32; 3]> {
    (0..n)
        .map(|_| match shape {
            Shape::Sphere => loop {
                let v = [r.random_range(-1.0f32..1.0), r.random_range(-1.0f32..1.0), r.random_range(-1.0f32..1.0)];
                let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                if l > 0.1 && l <= 1.0 {
                    break v.map(|x| x / l);
                }
            },
            Shape::Box => {
                let h = [1.0f32, 0.6, 0.4];
                let areas = [h[1] * h[2], h[0] * h[2], h[0] * h[1]];
                let total: f32 = areas.iter().sum();
                let mut u = r.random_range(0.0..total);
                let mut axis = 0;
                while axis < 2 && u > areas[axis] {
                    u -= areas[axis];
                    axis += 1;
                }
                let mut p = [0.0f32; 3];
                for a in 0..3 {
                    p[a] = r.random_range(-h[a]..h[a]);
                }
                p[axis] = if r.random_bool(0.5) { h[axis] } else { -h[axis] };
                p
            }
            Shape::Cylinder => {
                let th = r.random_range(0.0f32..std::f32::consts::TAU);
                if r.random_bool(0.2) {
                    let rad = 0.5 * r.random_range(0.0f32..1.0).sqrt();
                    [rad * th.cos(), rad * th.sin(), if r.random_bool(0.5) { 1.0 } else { -1.0 }]
                } else {
                    [0.5 * th.cos(), 0.5 * th.sin(), r.random_range(-1.0f32..1.0)]
                }
            }
        })
        .collect()
}

fn crop(points: &[[f32; 3]], keep: f32, r: &mut impl Rng) -> Vec<[f32; 3]> {
    let dir = loop {
        let v = [r.random_range(-1.0f32..1.0), r.random_range(-1.0f32..1.0), r.random_range(-1.0f32..1.0)];
        let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if l > 0.1 && l <= 1.0 {
            break v.map(|x| x / l);
        }
    };
    let mut d: Vec<(f32, usize)> =
        points.iter().enumerate().map(|(i, p)| (p[0] * dir[0] + p[1] * dir[1] + p[2] * dir[2], i)).collect();
    d.sort_by(|a, b| b.0.total_cmp(&a.0));
    let k = ((points.len() as f32) * keep) as usize;
    d[..k].iter().map(|&(_, i)| points[i]).collect()
}

fn subsample(points: &[[f32; 3]], n: usize, r: &mut impl Rng) -> Vec<[f32; 3]> {
    let mut idx: Vec<usize> = (0..points.len()).collect();
    for i in 0..n.min(idx.len()) {
        let j = r.random_range(i..idx.len());
        idx.swap(i, j);
    }
    (0..n).map(|i| points[idx[i % idx.len()]]).collect()
}

fn mean(p: &[[f32; 3]]) -> [f64; 3] {
    let mut m = [0.0f64; 3];
    for q in p {
        for a in 0..3 {
            m[a] += q[a] as f64 / p.len() as f64;
        }
    }
    m
}

/// A deterministic pair of `n` points per cloud.
pub fn pair(shape: Shape, n: usize, seed: u64) -> Pair {
    let mut r = rng(seed);
    let dense = sample(shape, 4 * n, &mut r);
    let centroid = mean(&dense);
    let src = subsample(&crop(&dense, 0.7, &mut r), n, &mut r);
    let tgt0 = subsample(&crop(&dense, 0.7, &mut r), n, &mut r);
    let deg = std::f64::consts::PI / 4.0;
    let rot = euler_xyz(r.random_range(-deg..deg), r.random_range(-deg..deg), r.random_range(-deg..deg));
    let dir = Vector3::new(r.random_range(-1.0..1.0), r.random_range(-1.0..1.0), r.random_range(-1.0..1.0)).normalize();
    let t_gt = from_rotation_translation(&rot, &(dir * r.random_range(0.0..0.5)));
    let mut noise = |p: [f32; 3]| p.map(|v| v + r.random_range(-0.01f32..0.01));
    let source: Vec<[f32; 3]> = src.into_iter().map(&mut noise).collect();
    let to_target = mapping(&t_gt);
    let target: Vec<[f32; 3]> = tgt0.iter().map(|p| noise(to_target(*p))).collect();
    let c = centroid.map(|v| v as f32);
    let (ms, mt) = (mean(&source), mean(&target));
    let ct = to_target(c);
    Pair {
        v_gt_source: [0, 1, 2].map(|a| (c[a] as f64 - ms[a]) as f32),
        v_gt_target: [0, 1, 2].map(|a| (ct[a] as f64 - mt[a]) as f32),
        source,
        target,
        t_gt,
    }
}

/// `count` pairs cycling through the three shapes, seeds `seed, seed + 1, ...`.
pub fn pairs(count: usize, n: usize, seed: u64) -> Vec<Pair> {
    let shapes = [Shape::Sphere, Shape::Box, Shape::Cylinder];
    (0..count).map(|i| pair(shapes[i % 3], n, seed + i as u64)).collect()
}
