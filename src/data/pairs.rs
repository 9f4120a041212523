//! The paper's pair protocol (docs/design.md §8), seeded per pair, and the mapping of a pair into
//! the frames the engine's network sees.
//!
//! Steps of [`make_pair`], in order:
//! 1. dense cloud: `dense_points` area-weighted surface samples of the mesh;
//! 2. normalise the **full** shape once: bounding-box centre to the origin, largest half-extent
//!    to 1 (so it fits `[-1, 1]^3` with its aspect ratio kept); then, only with
//!    [`PairParams::pose_angle_deg`] > 0 (not in the paper's protocol), turn it about the origin
//!    by random Euler angles; `c_full` = its mean;
//! 3. two half-space crops keeping `keep_ratio` of the dense points each: for a direction `u`
//!    uniform on S², keep the points with the largest `(p - c_full) · u`; both directions are
//!    redrawn until the overlap `|S ∩ T| / min(|S|, |T|)` is at least `min_overlap` (at most
//!    `max_crop_tries` draws; after that both sets are the same crop, along a fresh random
//!    direction, overlap 1); with [`PairParams::target_keep_ratio`] the target's crop keeps
//!    that fraction instead (1: the whole shape);
//! 4. each crop is resampled independently to exactly `points` points without replacement
//!    (padded with replacement if a crop is short; the target to [`PairParams::target_points`]
//!    when set);
//! 5. random rigid motion applied to the target: Euler angles `U[-a, a]` each,
//!    `R = Rx·Ry·Rz` ([`crate::transform::euler_xyz`]), translation `s·u`, `u` uniform on S²,
//!    `s ~ U[0, max_translation]`; GT `T_target_source = (R, t)`;
//! 6. both sets shuffled;
//! 7. Gaussian noise `σ = noise_sigma` on every coordinate of both sets, clipped to
//!    `±noise_clip`.

use crate::cloud::{grow_box, JointNormalization, PointCloud};
use crate::io::Mesh;
use crate::transform::{euler_xyz, from_rotation_translation};
use crate::{sampling, Result};
use nalgebra::{Matrix3, Matrix4, Vector3};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// The knobs of the protocol. [`Default`] is the paper's protocol; the trainer's curriculum
/// ramps `max_angle_deg`, `max_translation`, `keep_ratio`/`min_overlap` and `noise_sigma`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct PairParams {
    /// Dense surface samples of the full shape (default 4096).
    pub dense_points: usize,
    /// Points per set after resampling (default 1024).
    pub points: usize,
    /// When set, the target's points after resampling instead of `points` (a model sampled
    /// more densely than a scan of it). Default `None`: `points`.
    pub target_points: Option<usize>,
    /// Fraction of the dense points each half-space crop keeps (default 0.7).
    pub keep_ratio: f64,
    /// When set, the fraction of the dense points the target's crop keeps instead of
    /// `keep_ratio` (1: the whole shape, as when a scan is registered onto a model). Default
    /// `None`: the protocol's, both crops `keep_ratio`; the random draws are the same either way.
    pub target_keep_ratio: Option<f64>,
    /// Minimum overlap of the two crops' dense index sets (default 0.7).
    pub min_overlap: f64,
    /// Crop redraws before giving up on `min_overlap` (default 100).
    pub max_crop_tries: usize,
    /// Euler angles are drawn from `U[-max_angle_deg, max_angle_deg]`, degrees (default 45).
    pub max_angle_deg: f64,
    /// When set, the Euler angles about x and y are drawn from `U[-max_tilt_deg, max_tilt_deg]`
    /// instead (the one about z still from `max_angle_deg`): pairs whose clouds share the up axis
    /// z up to this tilt, as gravity-aligned scans do (default `None`: the protocol's).
    pub max_tilt_deg: Option<f64>,
    /// Translation length is drawn from `U[0, max_translation]`, normalised units (default 0.5).
    pub max_translation: f64,
    /// Noise standard deviation per coordinate, normalised units (default 0.01; 0 = no noise).
    pub noise_sigma: f64,
    /// Noise is clipped to `±noise_clip` (default 0.05).
    pub noise_clip: f64,
    /// Pose of the whole shape before cropping: Euler angles `U[-a, a]` each, degrees (default 0:
    /// the shape's own orientation, as in the paper's protocol, where ModelNet shapes come
    /// upright; 180 turns it anywhere). Drawn from a random stream of its own, so `0` leaves every
    /// pair exactly as it was. With it, the source is no longer in the shape's canonical pose: a
    /// network cannot lean on the category's usual orientation.
    pub pose_angle_deg: f64,
}

impl Default for PairParams {
    fn default() -> Self {
        Self {
            dense_points: 4096,
            points: 1024,
            target_points: None,
            keep_ratio: 0.7,
            target_keep_ratio: None,
            min_overlap: 0.7,
            max_crop_tries: 100,
            max_angle_deg: 45.0,
            max_tilt_deg: None,
            max_translation: 0.5,
            noise_sigma: 0.01,
            noise_clip: 0.05,
            pose_angle_deg: 0.0,
        }
    }
}

/// One registration pair in the normalised units of its full shape.
#[allow(non_snake_case)]
#[derive(Clone, Debug, PartialEq)]
pub struct Pair {
    /// The shape's name (`procedural/chair/12`, `bank/libigl/bunny.off`, ...).
    pub shape: String,
    /// The pair's seed: the same shape, params and seed give the same pair on every platform.
    pub seed: u64,
    /// Source points (canonical pose of the normalised shape, cropped, noisy, shuffled).
    pub source: Vec<[f32; 3]>,
    /// Target points (the other crop, moved by the GT motion, noisy, shuffled).
    pub target: Vec<[f32; 3]>,
    /// Ground truth: maps source points into the target frame, `p_t = R p_s + t`.
    pub T_target_source: Matrix4<f64>,
    /// The full (uncropped, dense) shape's mean in the source frame. **Not** pre-centred: subtract
    /// the source's own mean yourself if your network input is mean-centred (docs/design.md §11.2).
    pub centroid_source: [f64; 3],
    /// The same point in the target frame: `R c + t`. Not pre-centred either.
    pub centroid_target: [f64; 3],
    /// Overlap of the two crops, `|S ∩ T| / min(|S|, |T|)` on the dense indices, in [0, 1].
    pub overlap: f64,
    /// For each source point, its index in the dense cloud. Source point `i` and target point
    /// `k` are samples of the same surface point (before noise) iff their dense indices match.
    pub source_dense_index: Vec<u32>,
    /// For each target point, its index in the dense cloud.
    pub target_dense_index: Vec<u32>,
}

/// `Rx·Ry·Rz` ([`euler_xyz`]) with the three angles drawn in that order from `U[-max_deg, max_deg]`,
/// those about x and y from `U[-tilt, tilt]` when `max_tilt_deg` is set (the same draws either
/// way, so the rest of a pair does not change).
fn random_euler(rng: &mut ChaCha8Rng, max_deg: f64, max_tilt_deg: Option<f64>) -> Matrix3<f64> {
    let a = max_deg.to_radians();
    let tilt = max_tilt_deg.map_or(a, f64::to_radians);
    let mut unit = || rng.random::<f64>() * 2.0 - 1.0;
    let (ax, ay, az) = (unit() * tilt, unit() * tilt, unit() * a);
    euler_xyz(ax, ay, az)
}

/// Checks a [`PairParams::pose_angle_deg`] given by a user: a finite angle in [0, 360] degrees.
/// The error message starts with the value (`"400: expected ..."`).
pub fn check_pose_angle(deg: f64) -> std::result::Result<f64, String> {
    if deg.is_finite() && (0.0..=360.0).contains(&deg) {
        Ok(deg)
    } else {
        Err(format!("{deg}: expected degrees in [0, 360]"))
    }
}

/// Checks a [`PairParams::max_angle_deg`] given by a user (the range of the relative rotation's
/// Euler angles): a finite angle in [0, 180] degrees (180: any relative rotation). The error
/// message starts with the value (`"200: expected ..."`).
pub fn check_max_angle(deg: f64) -> std::result::Result<f64, String> {
    if deg.is_finite() && (0.0..=180.0).contains(&deg) {
        Ok(deg)
    } else {
        Err(format!("{deg}: expected degrees in [0, 180] (180: any relative rotation)"))
    }
}

/// Checks a share given by a user (of strays, of part-against-whole pairs): a finite number in
/// [0, 1]. The error message starts with the value (`"1.5: expected ..."`).
pub fn check_share(share: f64) -> std::result::Result<f64, String> {
    if share.is_finite() && (0.0..=1.0).contains(&share) {
        Ok(share)
    } else {
        Err(format!("{share}: expected a share in [0, 1]"))
    }
}

/// Normalises a cloud as the protocol does for a full shape: bounding-box centre to the origin,
/// largest half-extent to 1. Returns the cloud and the `(centre, scale)` used.
pub fn normalize_shape(cloud: &PointCloud) -> (PointCloud, [f64; 3], f64) {
    let (lo, hi) = cloud.bounds();
    let c = [0, 1, 2].map(|a| (lo[a] as f64 + hi[a] as f64) * 0.5);
    let s = (0..3).map(|a| (hi[a] as f64 - lo[a] as f64) * 0.5).fold(0.0, f64::max);
    let s = if s > 0.0 && s.is_finite() { s } else { 1.0 };
    let points = cloud.points.iter().map(|p| [0, 1, 2].map(|a| ((p[a] as f64 - c[a]) / s) as f32)).collect();
    (PointCloud::new(points), c, s)
}

/// A direction uniform on S²: φ ~ U[0, 2π), cos θ ~ U[-1, 1].
pub fn unit_vector(rng: &mut ChaCha8Rng) -> Vector3<f64> {
    let phi = rng.random::<f64>() * std::f64::consts::TAU;
    let z = rng.random::<f64>() * 2.0 - 1.0;
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vector3::new(r * phi.cos(), r * phi.sin(), z)
}

/// A standard normal draw (Box–Muller; platform-stable).
pub fn normal(rng: &mut ChaCha8Rng) -> f64 {
    let u1 = 1.0 - rng.random::<f64>(); // (0, 1]
    let u2 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// The indices of the `k` points with the largest `(p - c) · u`, sorted ascending.
fn half_space(points: &[[f32; 3]], c: &Vector3<f64>, u: &Vector3<f64>, k: usize) -> Vec<u32> {
    let mut d: Vec<(f64, u32)> = points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let v = Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64) - c;
            (v.dot(u), i as u32)
        })
        .collect();
    // the first k by distance along u, descending, ties by index: a strict total order, so the
    // k it selects are the same as a full sort's (and the same on every platform), in O(n)
    let k = k.min(d.len());
    if k > 0 && k < d.len() {
        d.select_nth_unstable_by(k - 1, |a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    }
    // ascending: mark the chosen and read the marks in order (O(n), no second sort)
    let mut chosen = vec![false; points.len()];
    for &(_, i) in &d[..k] {
        chosen[i as usize] = true;
    }
    (0..points.len() as u32).filter(|&i| chosen[i as usize]).collect()
}

fn overlap_of(a: &[u32], b: &[u32]) -> f64 {
    let (mut i, mut j, mut n) = (0, 0, 0usize);
    while i < a.len() && j < b.len() {
        match a[i].cmp(&b[j]) {
            std::cmp::Ordering::Less => i += 1,
            std::cmp::Ordering::Greater => j += 1,
            std::cmp::Ordering::Equal => {
                n += 1;
                i += 1;
                j += 1;
            }
        }
    }
    n as f64 / a.len().min(b.len()).max(1) as f64
}

/// `n` of `idx` without replacement (a partial Fisher–Yates), padded with replacement if short.
fn resample(idx: &[u32], n: usize, rng: &mut ChaCha8Rng) -> Vec<u32> {
    let mut pool = idx.to_vec();
    let take = n.min(pool.len());
    for i in 0..take {
        let j = rng.random_range(i..pool.len());
        pool.swap(i, j);
    }
    let mut out: Vec<u32> = pool[..take].to_vec();
    while out.len() < n && !idx.is_empty() {
        out.push(idx[rng.random_range(0..idx.len())]);
    }
    out
}

fn shuffle<T>(v: &mut [T], rng: &mut ChaCha8Rng) {
    for i in (1..v.len()).rev() {
        let j = rng.random_range(0..=i);
        v.swap(i, j);
    }
}

/// A pair from a mesh: samples `params.dense_points` on its surface (seeded from `seed`), then
/// [`pair_from_dense`]. Fails if the mesh has no area to sample.
pub fn make_pair(mesh: &Mesh, shape: &str, params: &PairParams, seed: u64) -> Result<Pair> {
    let dense = mesh.sample_surface(params.dense_points.max(1), super::mix(seed, 0xDE45E))?;
    Ok(pair_from_dense(&dense, shape, params, seed))
}

/// A pair from a dense cloud of a full shape (any units; it is normalised here, step 2).
pub fn pair_from_dense(dense: &PointCloud, shape: &str, params: &PairParams, seed: u64) -> Pair {
    let mut rng = sampling::rng(super::mix(seed, 0x9A1F));
    let (p, _, _) = normalize_shape(dense);
    let p = if params.pose_angle_deg > 0.0 {
        let mut pose_rng = sampling::rng(super::mix(seed, 0x905E));
        let pose = random_euler(&mut pose_rng, params.pose_angle_deg, None);
        p.transformed(&from_rotation_translation(&pose, &Vector3::zeros()))
    } else {
        p
    };
    let c = p.centroid();
    let cv = Vector3::from(c);
    let m = p.len();
    let kept = |ratio: f64| ((ratio.clamp(0.0, 1.0) * m as f64).round() as usize).clamp(1, m.max(1));
    let k = kept(params.keep_ratio);
    let k_target = params.target_keep_ratio.map_or(k, kept);

    // 3. crops with rejection
    let mut best = None;
    for _ in 0..params.max_crop_tries.max(1) {
        let (u1, u2) = (unit_vector(&mut rng), unit_vector(&mut rng));
        let s = half_space(&p.points, &cv, &u1, k);
        let t = half_space(&p.points, &cv, &u2, k_target);
        let o = overlap_of(&s, &t);
        if o >= params.min_overlap {
            best = Some((s, t, o));
            break;
        }
    }
    let (s_idx, t_idx, overlap) = best.unwrap_or_else(|| {
        let u = unit_vector(&mut rng);
        let s = half_space(&p.points, &cv, &u, k);
        let t = if k_target == k { s.clone() } else { half_space(&p.points, &cv, &u, k_target) };
        let o = overlap_of(&s, &t);
        (s, t, o)
    });

    // 4. independent resampling
    let mut src_i = resample(&s_idx, params.points, &mut rng);
    let mut tgt_i = resample(&t_idx, params.target_points.unwrap_or(params.points), &mut rng);

    // 5. rigid motion
    let r = random_euler(&mut rng, params.max_angle_deg, params.max_tilt_deg);
    let t = unit_vector(&mut rng) * (rng.random::<f64>() * params.max_translation);
    let gt = from_rotation_translation(&r, &t);

    // 6. shuffle (the order of the index lists is already random; shuffle once more so the
    // order does not depend on the resampling scheme), then 7. noise
    shuffle(&mut src_i, &mut rng);
    shuffle(&mut tgt_i, &mut rng);
    let sigma = params.noise_sigma.max(0.0);
    let clip = params.noise_clip.max(0.0);
    let jitter = |rng: &mut ChaCha8Rng, q: Vector3<f64>| -> [f32; 3] {
        let mut out = [0.0f32; 3];
        for a in 0..3 {
            out[a] = (q[a] + noise(rng, sigma, clip)) as f32;
        }
        out
    };
    let pt = |i: u32| {
        let v = p.points[i as usize];
        Vector3::new(v[0] as f64, v[1] as f64, v[2] as f64)
    };
    let source: Vec<[f32; 3]> = src_i.iter().map(|&i| jitter(&mut rng, pt(i))).collect();
    let target: Vec<[f32; 3]> = tgt_i.iter().map(|&i| jitter(&mut rng, r * pt(i) + t)).collect();
    let ct = r * cv + t;
    Pair {
        shape: shape.to_string(),
        seed,
        source,
        target,
        T_target_source: gt,
        centroid_source: c,
        centroid_target: [ct.x, ct.y, ct.z],
        overlap,
        source_dense_index: src_i,
        target_dense_index: tgt_i,
    }
}

/// One coordinate's noise: Gaussian of `sigma` clipped to `±clip`, nothing (and no draw) when
/// `sigma` is 0.
fn noise(rng: &mut ChaCha8Rng, sigma: f64, clip: f64) -> f64 {
    if sigma > 0.0 {
        (normal(rng) * sigma).clamp(-clip, clip)
    } else {
        0.0
    }
}

/// Half-side of the cube (about the normalised shape's centre, which fits `[-1, 1]^3`) that
/// [`add_strays`] scatters its points in: three times the shape's size.
pub const STRAY_EXTENT: f64 = 3.0;

/// The dense index of a point that is no surface sample of the shape: a stray ([`add_strays`])
/// or a support plane's ([`add_support`]).
pub const STRAY_INDEX: u32 = u32::MAX;

/// Adds stray returns to `pair` (not in the paper's protocol): `round(source_ratio * n)` points
/// to its source of `n` points, drawn uniformly in the cube of half-side [`STRAY_EXTENT`] about
/// the source frame's origin, and `round(target_ratio * m)` to its target, drawn in the same cube
/// moved by the ground truth, appended after the surface points with the dense index
/// [`STRAY_INDEX`]. Drawn from a random stream of their own (from the pair's seed), so the
/// surface points are the pair's as they were. Ratios are clamped to `[0, 1]`.
pub fn add_strays(pair: &mut Pair, source_ratio: f64, target_ratio: f64) {
    let mut rng = sampling::rng(super::mix(pair.seed, 0x57A4));
    let count = |ratio: f64, n: usize| (ratio.clamp(0.0, 1.0) * n as f64).round() as usize;
    let (n_source, n_target) = (count(source_ratio, pair.source.len()), count(target_ratio, pair.target.len()));
    let stray = |rng: &mut ChaCha8Rng| {
        let mut v = || (rng.random::<f64>() * 2.0 - 1.0) * STRAY_EXTENT;
        nalgebra::Point3::new(v(), v(), v())
    };
    for _ in 0..n_source {
        let p = stray(&mut rng);
        pair.source.push([p.x as f32, p.y as f32, p.z as f32]);
        pair.source_dense_index.push(STRAY_INDEX);
    }
    for _ in 0..n_target {
        let p = pair.T_target_source.transform_point(&stray(&mut rng));
        pair.target.push([p.x as f32, p.y as f32, p.z as f32]);
        pair.target_dense_index.push(STRAY_INDEX);
    }
}

/// How far [`add_support`]'s square reaches beyond the source's footprint on each side, in the
/// source's largest half-extents: a table reaching out about half the object's size.
pub const SUPPORT_EXTENT: f64 = 1.0;

/// The square of [`add_support`] under the object in one of `pair`'s frames (the target's
/// with `in_target`): its centre's x and y and its half-side from that cloud's surface points
/// (those with a dense index other than [`STRAY_INDEX`]), its height the lowest of both clouds'
/// surface points in that frame (the object stands on it, whatever each crop kept of its bottom).
fn support_square(pair: &Pair, in_target: bool) -> Option<(f64, f64, f64, f64)> {
    fn surface<'a>(points: &'a [[f32; 3]], index: &'a [u32]) -> impl Iterator<Item = &'a [f32; 3]> {
        points.iter().zip(index).filter(|(_, &i)| i != STRAY_INDEX).map(|(p, _)| p)
    }
    let (source, target) =
        (surface(&pair.source, &pair.source_dense_index), surface(&pair.target, &pair.target_dense_index));
    let (own, other, to_own) = if in_target {
        (target, source, pair.T_target_source)
    } else {
        (source, target, crate::transform::rigid_inverse(&pair.T_target_source))
    };
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for p in own {
        grow_box(&mut lo, &mut hi, p);
    }
    if !lo[0].is_finite() {
        return None;
    }
    let (lo, hi) = (lo.map(f64::from), hi.map(f64::from));
    let floor =
        other.map(|p| to_own.transform_point(&nalgebra::Point3::from(p.map(f64::from))).z).fold(lo[2], f64::min);
    let extent = |a: usize| (hi[a] - lo[a]) * 0.5;
    let half = extent(0).max(extent(1)) + SUPPORT_EXTENT * extent(0).max(extent(1)).max(extent(2));
    Some(((lo[0] + hi[0]) * 0.5, (lo[1] + hi[1]) * 0.5, floor, half))
}

/// Adds a support plane to `pair` (a table or floor the scanned object stands on; not in the
/// paper's protocol): `round(source_ratio * n)` points to its source of `n` points, drawn
/// uniformly over a square that is level in the source frame (z up, as the bank's shapes mostly
/// stand), at the height of the object's lowest point (of both clouds' surface points), centred
/// under the source's footprint and reaching [`SUPPORT_EXTENT`] times the source's largest
/// half-extent beyond it, with Gaussian noise of `sigma` (clipped at `clip`) across it; and `round(target_ratio * m)` points to its
/// target: of the same plane moved by the ground truth (the same table in both scans, the object
/// not moved on it), or, with `moved`, of the square that is level in the target's frame under
/// the target's own points (the object moved on the table between the scans: the table does not
/// follow the ground truth; pairs made with `max_tilt_deg` 0 turn the object about the table's
/// normal only). Appended after the surface points with the dense index [`STRAY_INDEX`] (no
/// surface sample of the shape), from a random stream of their own, so the surface points are
/// the pair's as they were. Ratios are clamped to `[0, 1]`; a cloud without surface points gets
/// none.
pub fn add_support(pair: &mut Pair, source_ratio: f64, target_ratio: f64, moved: bool, sigma: f64, clip: f64) {
    let mut rng = sampling::rng(super::mix(pair.seed, 0x5AB1E));
    let count = |ratio: f64, n: usize| (ratio.clamp(0.0, 1.0) * n as f64).round() as usize;
    let (n_source, n_target) = (count(source_ratio, pair.source.len()), count(target_ratio, pair.target.len()));
    let (sigma, clip) = (sigma.max(0.0), clip.max(0.0));
    let plane = |rng: &mut ChaCha8Rng, (cx, cy, floor, half): (f64, f64, f64, f64)| {
        let x = cx + (rng.random::<f64>() * 2.0 - 1.0) * half;
        let y = cy + (rng.random::<f64>() * 2.0 - 1.0) * half;
        let z = floor + noise(rng, sigma, clip);
        nalgebra::Point3::new(x, y, z)
    };
    let Some(under_source) = support_square(pair, false) else { return };
    for _ in 0..n_source {
        let p = plane(&mut rng, under_source);
        pair.source.push([p.x as f32, p.y as f32, p.z as f32]);
        pair.source_dense_index.push(STRAY_INDEX);
    }
    let under_target = if moved { support_square(pair, true) } else { None };
    for _ in 0..n_target {
        let p = match under_target {
            Some(square) => plane(&mut rng, square),
            None if moved => break,
            None => pair.T_target_source.transform_point(&plane(&mut rng, under_source)),
        };
        pair.target.push([p.x as f32, p.y as f32, p.z as f32]);
        pair.target_dense_index.push(STRAY_INDEX);
    }
}

/// A pair in the frames the engine's network sees ([`crate::Registrar::register`]): each cloud
/// centred on its own bounding-box centre and both divided by one shared scale
/// ([`JointNormalization::of_pair`]); the GT and the centroids mapped accordingly.
#[allow(non_snake_case)]
#[derive(Clone, Debug, PartialEq)]
pub struct EnginePair {
    /// The source, normalised.
    pub source: PointCloud,
    /// The target, normalised.
    pub target: PointCloud,
    /// GT in the normalised frames: `N_t · T · N_s⁻¹` (still rigid: the scale is shared).
    pub T_target_source: Matrix4<f64>,
    /// The full-shape centroid in the normalised source frame (not pre-centred).
    pub centroid_source: [f64; 3],
    /// The full-shape centroid in the normalised target frame (not pre-centred).
    pub centroid_target: [f64; 3],
    /// The normalisation used (to map results back to the pair's units).
    pub norm: JointNormalization,
}

/// The seed offset the engine uses for the target's network sample (the source uses the seed
/// itself). Mirrors `register.rs`; keep in sync.
pub const TARGET_SAMPLE_SEED_XOR: u64 = sampling::TARGET_SEED_XOR;

impl Pair {
    /// The pair in the engine's network frames (see [`EnginePair`]).
    pub fn engine_frames(&self) -> EnginePair {
        let src = PointCloud::new(self.source.clone());
        let tgt = PointCloud::new(self.target.clone());
        let norm = JointNormalization::of_pair(&src, &tgt);
        let ns = norm.source_to_normalized();
        let nt = norm.target_to_normalized();
        let map = |m: &Matrix4<f64>, c: [f64; 3]| {
            let v = m * nalgebra::Vector4::new(c[0], c[1], c[2], 1.0);
            [v.x, v.y, v.z]
        };
        EnginePair {
            source: src.transformed(&ns),
            target: tgt.transformed(&nt),
            T_target_source: norm.normalize_transform(&self.T_target_source),
            centroid_source: map(&ns, self.centroid_source),
            centroid_target: map(&nt, self.centroid_target),
            norm,
        }
    }
}

impl EnginePair {
    /// The `n` network points of each cloud, drawn exactly as the engine draws them for
    /// `Options::seed = seed` ([`sampling::network_sample`]; the target's seed is
    /// `seed ^ TARGET_SAMPLE_SEED_XOR`), so training inputs match inference inputs.
    pub fn network_sample(&self, n: usize, seed: u64) -> (PointCloud, PointCloud) {
        (
            sampling::network_sample(&self.source, n, seed),
            sampling::network_sample(&self.target, n, seed ^ TARGET_SAMPLE_SEED_XOR),
        )
    }
}
