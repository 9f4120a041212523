//! Fast Point Feature Histograms (Rusu et al. 2009), the descriptor Open3D computes
//! (`pipelines/registration/Feature.cpp`): per point, a 33-bin histogram of the Darboux-frame
//! angles to its neighbours (three angle features, 11 bins each), re-weighted by the neighbours'
//! own histograms.
//!
//! Neighbourhoods are the `k` nearest points within a radius (the crate's [`KdIndex`]); normals
//! are PCA normals oriented away from the cloud's centroid, which turns with the cloud, so the
//! signed angle features agree between two views of one surface.

use crate::spatial::KdIndex;

/// Bins per angle feature.
pub const BINS: usize = 11;
/// Length of a descriptor: three features of [`BINS`] bins.
pub const DIM: usize = 3 * BINS;
/// One descriptor.
pub type Descriptor = [f32; DIM];

/// Where the neighbourhoods of [`describe`] end.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FpfhParams {
    /// Normals: PCA over the neighbours within this radius (at most [`FpfhParams::normal_max`]).
    pub normal_radius: f64,
    /// Most neighbours of a normal.
    pub normal_max: usize,
    /// Histograms: neighbours within this radius (at most [`FpfhParams::feature_max`]).
    pub feature_radius: f64,
    /// Most neighbours of a histogram.
    pub feature_max: usize,
}

impl FpfhParams {
    /// Open3D's tutorial settings for voxel size `v`: normals within `2v` (at most 30
    /// neighbours), histograms within `5v` (at most 100).
    pub fn for_voxel(v: f64) -> Self {
        Self { normal_radius: 2.0 * v, normal_max: 30, feature_radius: 5.0 * v, feature_max: 100 }
    }
}

/// The `max` nearest points of `q` within `radius` (the point itself included), into `out`.
fn neighbours(index: &KdIndex, q: &[f32; 3], radius: f64, max: usize, out: &mut Vec<(usize, f32)>) {
    index.within_into(q, (radius * radius) as f32, max, out);
}

/// Unit normals (PCA over each point's radius neighbourhood, at least its 3 nearest points),
/// each oriented away from the cloud's centroid.
pub fn oriented_normals(points: &[[f32; 3]], index: &KdIndex, radius: f64, max: usize) -> Vec<[f32; 3]> {
    let n = points.len().max(1) as f64;
    let mut c = [0.0f64; 3];
    for p in points {
        for a in 0..3 {
            c[a] += p[a] as f64 / n;
        }
    }
    let mut nb = Vec::with_capacity(max + 1);
    let mut near = Vec::with_capacity(4);
    points
        .iter()
        .map(|q| {
            neighbours(index, q, radius, max.max(3), &mut nb);
            if nb.len() < 3 {
                index.knn_into(q, 3, &mut near);
                nb.clone_from(&near);
            }
            let mut normal = crate::normals::normal_of(points, nb.iter().map(|e| e.0));
            let out = [0, 1, 2].map(|a| q[a] as f64 - c[a]);
            let dot: f64 = (0..3).map(|a| normal[a] as f64 * out[a]).sum();
            if dot < 0.0 {
                normal = normal.map(|v| -v);
            }
            normal
        })
        .collect()
}

fn sub(a: &[f32; 3], b: &[f32; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| a[i] as f64 - b[i] as f64)
}
fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
fn f64s(v: &[f32; 3]) -> [f64; 3] {
    v.map(|x| x as f64)
}

/// The three angle features of a point pair (Open3D's `ComputePairFeatures`): `(f1, f2, f3)`
/// with `f1` in `[-pi, pi]`, `f2` and `f3` in `[-1, 1]`; `None` for coincident points or a
/// degenerate frame.
pub fn pair_features(p1: &[f32; 3], n1: &[f32; 3], p2: &[f32; 3], n2: &[f32; 3]) -> Option<[f64; 3]> {
    features_and_tie(p1, n1, p2, n2).0
}

/// [`pair_features`], and whether the pair's two angles tie (`|angle1| == |angle2|`). The
/// features order the pair by those angles (the point whose normal is nearer the line between
/// them first), so the pair taken the other way round gives the same features, bit for bit
/// (the line's direction only changes sign, which negation does exactly), unless they tie.
fn features_and_tie(p1: &[f32; 3], n1: &[f32; 3], p2: &[f32; 3], n2: &[f32; 3]) -> (Option<[f64; 3]>, bool) {
    let mut d = sub(p2, p1);
    let len = dot(&d, &d).sqrt();
    if len == 0.0 {
        return (None, false);
    }
    let (mut a, mut b) = (f64s(n1), f64s(n2));
    let angle1 = dot(&a, &d) / len;
    let angle2 = dot(&b, &d) / len;
    let tie = angle1.abs() == angle2.abs();
    // acos(|angle1|) > acos(|angle2|), acos being decreasing
    let f3 = if angle1.abs() < angle2.abs() {
        std::mem::swap(&mut a, &mut b);
        d = d.map(|v| -v);
        -angle2
    } else {
        angle1
    };
    let v = cross(&d, &a);
    let vn = dot(&v, &v).sqrt();
    if vn == 0.0 {
        return (None, tie);
    }
    let v = v.map(|x| x / vn);
    let w = cross(&a, &v);
    let f2 = dot(&v, &b);
    let f1 = dot(&w, &b).atan2(dot(&a, &b));
    (Some([f1, f2, f3]), tie)
}

fn bin(x: f64, lo: f64, hi: f64) -> usize {
    let i = ((x - lo) / (hi - lo) * BINS as f64).floor();
    if i.is_nan() {
        0
    } else {
        (i.max(0.0) as usize).min(BINS - 1)
    }
}

/// The FPFH descriptor of every point (Open3D's definition: SPFH in percent per feature, then
/// each point's SPFH plus the inverse-squared-distance weighted sum of its neighbours' SPFH, each
/// feature's block of that sum scaled to 100). `normals` are unit normals, one per point.
/// Points without neighbours get an all-zero descriptor.
///
/// Each pair of neighbours is computed once where both points' neighbourhoods hold the other
/// ([`pair_features`] orders a pair by its normals' angles to the line between the points, so it
/// gives the same features both ways, bit for bit, unless those angles tie) and
/// counted in both histograms; every increment of one histogram is the same value, so the order
/// they come in does not change it.
pub fn describe(points: &[[f32; 3]], normals: &[[f32; 3]], index: &KdIndex, params: &FpfhParams) -> Vec<Descriptor> {
    let cap = params.feature_max + 1;
    let mut nb = Vec::with_capacity(cap);
    // each point's neighbourhood (also reused by the weighting pass), and where a neighbourhood
    // was cut at `cap` points, its farthest squared distance
    let mut lists: Vec<(u32, u32)> = Vec::with_capacity(points.len());
    let mut cut: Vec<f32> = Vec::with_capacity(points.len());
    let mut flat: Vec<(u32, f32)> = Vec::new();
    for (i, q) in points.iter().enumerate() {
        neighbours(index, q, params.feature_radius, cap, &mut nb);
        let start = flat.len() as u32;
        flat.extend(nb.iter().filter(|e| e.0 != i).map(|e| (e.0 as u32, e.1)));
        lists.push((start, flat.len() as u32));
        cut.push(if nb.len() >= cap { nb.last().map_or(f32::INFINITY, |e| e.1) } else { f32::INFINITY });
    }
    let others = |i: usize| &flat[lists[i].0 as usize..lists[i].1 as usize];
    // whether `a`, at squared distance `d2` from `b` (within the radius), is in `b`'s neighbourhood
    // (the index's squared distance of a pair is the same from either side: the differences only
    // change sign); a tie with the cut's distance is looked up
    let holds = |b: usize, a: usize, d2: f32| {
        if d2 != cut[b] {
            d2 < cut[b]
        } else {
            others(b).iter().any(|e| e.0 as usize == a)
        }
    };
    let inc = |i: usize| if others(i).is_empty() { 0.0 } else { 100.0 / others(i).len() as f32 };
    let add = |h: &mut [f32; DIM], f: Option<[f64; 3]>, inc: f32| {
        if let Some([f1, f2, f3]) = f {
            h[bin(f1, -std::f64::consts::PI, std::f64::consts::PI)] += inc;
            h[BINS + bin(f2, -1.0, 1.0)] += inc;
            h[2 * BINS + bin(f3, -1.0, 1.0)] += inc;
        }
    };
    // SPFH
    let mut spfh = vec![[0.0f32; DIM]; points.len()];
    for (i, q) in points.iter().enumerate() {
        let inc_i = inc(i);
        for &(j, d2) in others(i) {
            let j = j as usize;
            let shared = holds(j, i, d2);
            if j < i && shared {
                // counted when `j` took the pair
                continue;
            }
            let (f, tie) = features_and_tie(q, &normals[i], &points[j], &normals[j]);
            add(&mut spfh[i], f, inc_i);
            if j > i && shared {
                let f = if tie { pair_features(&points[j], &normals[j], q, &normals[i]) } else { f };
                add(&mut spfh[j], f, inc(j));
            }
        }
    }
    lists
        .iter()
        .enumerate()
        .map(|(i, &(a, b))| {
            let mut f = [0.0f32; DIM];
            let mut sum = [0.0f32; 3];
            for &(j, d2) in &flat[a as usize..b as usize] {
                if d2 <= 0.0 {
                    continue;
                }
                let inv = 1.0 / d2;
                let h = &spfh[j as usize];
                // feature by feature, each block's sum in a local (the same additions, in the
                // same order, as one pass over the 33 bins; but no store-to-load chain)
                for (block, s) in sum.iter_mut().enumerate() {
                    let bins = block * BINS..(block + 1) * BINS;
                    let mut acc_sum = *s;
                    for (acc, &v) in f[bins.clone()].iter_mut().zip(&h[bins]) {
                        let v = v * inv;
                        *acc += v;
                        acc_sum += v;
                    }
                    *s = acc_sum;
                }
            }
            let mut out = [0.0f32; DIM];
            for k in 0..DIM {
                let s = if sum[k / BINS] != 0.0 { 100.0 / sum[k / BINS] } else { 0.0 };
                out[k] = f[k] * s + spfh[i][k];
            }
            out
        })
        .collect()
}
