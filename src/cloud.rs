//! Point clouds: the owned `f32` xyz type with an `f64` origin, validation, and the joint
//! normalisation.
//!
//! Coordinates far from zero (map grids, UTM: 5e6 m) do not fit `f32` with their shape intact,
//! so a cloud stores `f32` offsets from an `f64` origin: point `i` in the caller's frame is
//! `origin + points[i]`, computed in `f64`. Readers and [`PointCloud::from_xyz_f64`] choose the
//! origin ([`PointCloud::from_points_f64`]) before anything becomes `f32`; the pipeline works on
//! the offsets and composes its answer with the origins in `f64`.
//!
//! Downsampling lives in [`crate::sampling`], normals in [`crate::normals`].

use crate::{Error, Result};
use nalgebra::{Matrix4, Vector3};

/// The fewest points a cloud may have to be registered.
pub const MIN_POINTS: usize = 16;

/// How many distinct points `points` holds, counted up to `k` (it stops there): a cloud of 12
/// points repeated 2,000 times is 12 points, not 24,000. Reads only until `k` are found.
pub fn distinct_up_to(points: &[[f32; 3]], k: usize) -> usize {
    let mut seen = std::collections::HashSet::with_capacity(k.min(points.len()));
    for p in points {
        // +0.0 and -0.0 are one point
        seen.insert(p.map(|v| (v + 0.0).to_bits()));
        if seen.len() >= k {
            break;
        }
    }
    seen.len()
}

/// Ratio of a cloud's distance from zero (largest absolute coordinate of its bounding-box centre)
/// to its size (largest half-extent) above which [`PointCloud::from_points_f64`] moves the
/// origin to the bounding-box centre. Below it, `f32` keeps the shape to about `16 * 2^-24`
/// (1e-6) of the cloud's size, and the points are stored as they are (origin zero).
pub const RECENTER_RATIO: f64 = 16.0;

/// An owned cloud of `f32` xyz points, offsets from an `f64` origin.
///
/// Point `i` in the caller's frame is `origin + points[i]` (in `f64`). [`PointCloud::new`] has
/// origin zero; readers and [`PointCloud::from_xyz_f64`] pick an origin near the points when they
/// are far from zero, so large coordinates keep their shape. Bounds, extents and centroids are
/// of `points` (relative to the origin).
///
/// Readers fill it faithfully (a PCD "no return" stays NaN); [`PointCloud::validated`] is where
/// non-finite points are rejected or dropped, before any numerical work.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PointCloud {
    /// The points relative to [`PointCloud::origin`], `[x, y, z]` each.
    pub points: Vec<[f32; 3]>,
    /// Where `points` are measured from, in the caller's frame.
    pub origin: [f64; 3],
}

/// Axis-aligned bounds `(min, max)` of `points`; both zero when there are none
/// ([`PointCloud::bounds`]).
pub(crate) fn bounds_of(points: &[[f32; 3]]) -> ([f32; 3], [f32; 3]) {
    if points.is_empty() {
        return ([0.0; 3], [0.0; 3]);
    }
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in points {
        grow_box(&mut lo, &mut hi, p);
    }
    (lo, hi)
}

/// The largest coordinate a point may have (its offset from the cloud's origin): beyond it the
/// squared distances the engine computes in `f32` overflow (a sensor's `f32::MAX` for "no
/// return"), and [`NonFinite`] treats the point as it treats a NaN.
pub const MAX_COORDINATE: f32 = 1e18;

/// Whether every coordinate of `p` is finite and within [`MAX_COORDINATE`].
fn is_usable(p: &[f32; 3]) -> bool {
    p.iter().all(|v| v.abs() <= MAX_COORDINATE)
}

/// What to do with points that have a NaN or infinite coordinate, or one beyond
/// [`MAX_COORDINATE`] (1e18) from the cloud's origin.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "camelCase")]
#[cfg_attr(feature = "ts", derive(ts_rs::TS), ts(rename = "NonFinite"))]
pub enum NonFinite {
    /// Fail with an error naming the first bad point (the default).
    #[default]
    Error,
    /// Drop such points silently (e.g. organised PCD clouds, where NaN means "no return").
    Drop,
}

impl PointCloud {
    /// The cloud without the points at `indices` (ascending, each at most once), its origin
    /// kept.
    pub fn without(mut self, indices: &[usize]) -> Self {
        let mut next = indices.iter().peekable();
        let mut i = 0usize;
        self.points.retain(|_| {
            let drop = next.next_if(|&&f| f == i).is_some();
            i += 1;
            !drop
        });
        self
    }

    /// Wraps points without checking them (origin zero: the points are in the caller's frame).
    pub fn new(points: Vec<[f32; 3]>) -> Self {
        Self { points, origin: [0.0; 3] }
    }

    /// Wraps offsets from `origin` without checking them: point `i` is `origin + points[i]`.
    pub fn with_origin(points: Vec<[f32; 3]>, origin: [f64; 3]) -> Self {
        Self { points, origin }
    }

    /// From `f64` points in the caller's frame, keeping their shape: when the cloud is far from
    /// zero relative to its size (more than [`RECENTER_RATIO`] times), the origin becomes the
    /// `f64` bounding-box centre of its bulk (the points finite in `f32`, strays far from the rest
    /// left out of the box: [`STRAY_SPREADS`]) and the offsets are stored as `f32`; otherwise the
    /// origin is zero and the points are stored as they are. Non-finite points stay
    /// non-finite ([`PointCloud::validated`] deals with them).
    pub fn from_points_f64(points: &[[f64; 3]]) -> Self {
        let origin = choose_origin(points.len(), |i| points[i]);
        let cloud = points.iter().map(|p| [0, 1, 2].map(|a| (p[a] - origin[a]) as f32)).collect();
        Self { points: cloud, origin }
    }

    /// From a packed `f64` `[x0, y0, z0, x1, ...]` buffer (the JS `Float64Array` layout), keeping
    /// large coordinates' shape as [`PointCloud::from_points_f64`] does. Fails if the length is
    /// not a multiple of 3.
    pub fn from_xyz_f64(flat: &[f64]) -> Result<Self> {
        if !flat.len().is_multiple_of(3) {
            return Err(Error::InvalidCloud(format!(
                "packed xyz buffer has length {}, which is not a multiple of 3",
                flat.len()
            )));
        }
        let triples = || flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]);
        let origin = choose_origin(flat.len() / 3, |i| [flat[3 * i], flat[3 * i + 1], flat[3 * i + 2]]);
        let points = triples().map(|p| [0, 1, 2].map(|a| (p[a] - origin[a]) as f32)).collect();
        Ok(Self { points, origin })
    }

    /// Point `i` in the caller's frame, in `f64` (`origin + points[i]`).
    pub fn point_f64(&self, i: usize) -> [f64; 3] {
        let p = self.points[i];
        [0, 1, 2].map(|a| self.origin[a] + p[a] as f64)
    }

    /// True when the origin is zero (the points are in the caller's frame).
    pub fn origin_is_zero(&self) -> bool {
        self.origin == [0.0; 3]
    }

    /// From a packed `[x0, y0, z0, x1, ...]` buffer (the JS `Float32Array` layout).
    /// Fails if the length is not a multiple of 3.
    pub fn from_xyz(flat: &[f32]) -> Result<Self> {
        if !flat.len().is_multiple_of(3) {
            return Err(Error::InvalidCloud(format!(
                "packed xyz buffer has length {}, which is not a multiple of 3",
                flat.len()
            )));
        }
        Ok(Self::new(flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()))
    }

    /// The packed `[x0, y0, z0, x1, ...]` layout, in the caller's frame (`origin + points[i]`
    /// rounded to `f32`; exactly `points` when the origin is zero).
    pub fn to_xyz(&self) -> Vec<f32> {
        if self.origin_is_zero() {
            return self.points.iter().flatten().copied().collect();
        }
        (0..self.len()).flat_map(|i| self.point_f64(i)).map(|v| v as f32).collect()
    }

    /// The packed `[x0, y0, z0, x1, ...]` layout in the caller's frame, in `f64`.
    pub fn to_xyz_f64(&self) -> Vec<f64> {
        (0..self.len()).flat_map(|i| self.point_f64(i)).collect()
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when the cloud has no points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Checks the cloud for registration: non-finite points are an error naming the first bad
    /// index (or are dropped, with [`NonFinite::Drop`]); fewer than `min_points` points is an
    /// error; so is a cloud whose points all coincide. `what` names the cloud in messages
    /// (`"source"`, `"target"`).
    pub fn validated(&self, what: &str, min_points: usize, non_finite: NonFinite) -> Result<PointCloud> {
        match (self.points.iter().position(|p| !is_usable(p)), non_finite) {
            // only the finite points are copied
            (Some(_), NonFinite::Drop) => {
                let cloud =
                    PointCloud { points: self.points.iter().copied().filter(is_usable).collect(), origin: self.origin };
                cloud.check(what, min_points, None)?;
                Ok(cloud)
            }
            // checked before the copy: a cloud that fails costs no copy of its points
            (bad, _) => {
                self.check(what, min_points, bad)?;
                Ok(self.clone())
            }
        }
    }

    /// [`PointCloud::validated`], keeping the cloud's own points (without a copy of a large one).
    pub fn into_validated(self, what: &str, min_points: usize, non_finite: NonFinite) -> Result<PointCloud> {
        let mut cloud = self;
        let mut bad = cloud.points.iter().position(|p| !is_usable(p));
        if bad.is_some() && non_finite == NonFinite::Drop {
            cloud.points.retain(is_usable);
            bad = None;
        }
        cloud.check(what, min_points, bad)?;
        Ok(cloud)
    }

    /// The checks of [`PointCloud::validated`] on a cloud whose first non-finite point (to be
    /// reported) is `bad`: that point, fewer than `min_points` points, or zero extent is an error.
    fn check(&self, what: &str, min_points: usize, bad: Option<usize>) -> Result<()> {
        if let Some(i) = bad {
            // in the caller's frame (the offsets from the origin are internal)
            let (p, given) = (self.points[i], self.point_f64(i));
            return Err(Error::InvalidCloud(if p.iter().all(|v| v.is_finite()) {
                format!(
                    "{what} point {i} has a coordinate beyond 1e18 from the cloud's origin ({given:?}), where distances \
                     overflow f32 (a sensor's f32::MAX for \"no return\"?): drop such points with `nonFinite: \"drop\"`"
                )
            } else {
                format!(
                    "{what} point {i} has a non-finite coordinate {given:?} (NaN, infinite, or too large for f32's range, \
                     3.4e38; drop such points with `nonFinite: \"drop\"`)"
                )
            }));
        }
        if self.len() < min_points {
            return Err(Error::InvalidCloud(format!(
                "{what} has {} finite points; at least {min_points} are needed",
                self.len()
            )));
        }
        let (lo, hi) = self.bounds();
        let extent = (0..3).map(|a| hi[a] - lo[a]).fold(0.0f32, f32::max);
        if extent <= 0.0 {
            return Err(Error::InvalidCloud(format!("{what} has zero extent: all {} points coincide", self.len())));
        }
        let distinct = distinct_up_to(&self.points, min_points);
        if distinct < min_points {
            return Err(Error::InvalidCloud(format!(
                "{what} has {} finite points but only {distinct} distinct ones (the others repeat them); at least \
                 {min_points} distinct points are needed",
                self.len()
            )));
        }
        Ok(())
    }

    /// Axis-aligned bounds `(min, max)` of `points` (relative to the origin). For an empty cloud
    /// both are zero.
    pub fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        bounds_of(&self.points)
    }

    /// The largest half-extent of the axis-aligned bounds (0 for an empty cloud).
    pub fn half_extent(&self) -> f64 {
        let (lo, hi) = self.bounds();
        half_extent_of(lo, hi)
    }

    /// The mean of `points` (relative to the origin), accumulated in `f64`.
    pub fn centroid(&self) -> [f64; 3] {
        centroid_of(&self.points)
    }

    /// A copy with every point mapped by the rigid (or similarity) transform `m`, in the
    /// caller's frame. With origin zero the points are mapped and the origin stays zero; otherwise
    /// the origin is mapped in `f64` and the offsets by `m`'s linear part, so large coordinates
    /// keep their shape. To save or draw a cloud in another frame, [`PointCloud::placed`] also
    /// keeps the digits of a cloud near zero moved far from it.
    pub fn transformed(&self, m: &Matrix4<f64>) -> PointCloud {
        let (map, origin) = self.mapping(m);
        let apply = crate::transform::mapping(&map);
        PointCloud::with_origin(self.points.iter().map(|&p| apply(p)).collect(), origin)
    }

    /// The cloud placed by the rigid (or similarity) transform `m` into another frame, for
    /// output (saving it, drawing it there): [`PointCloud::transformed`], except for a cloud with
    /// origin zero that `m` places so far from zero for its size that `f32` would round its
    /// points there by more than [`crate::checks::F32_ROUNDING_WARNING`] of its half-extent (a
    /// local scan placed on a map grid): it gets its box's centre, placed, as its origin, in
    /// `f64`, and its points turned by `m`'s linear part about that centre as offsets from it, so
    /// the placed points keep their digits.
    pub fn placed(&self, m: &Matrix4<f64>) -> PointCloud {
        let (lo, hi) = self.bounds();
        let half = half_extent_of(lo, hi);
        let centre = [0, 1, 2].map(|a| lo[a] as f64 * 0.5 + hi[a] as f64 * 0.5);
        let landed = m.transform_point(&nalgebra::Point3::from(centre));
        let far = landed.iter().fold(0.0f64, |a, v| a.max(v.abs())) + half;
        if !self.origin_is_zero() || !crate::checks::f32_rounds(far, half) {
            return self.transformed(m);
        }
        let mut linear = *m;
        linear.fixed_view_mut::<3, 1>(0, 3).fill(0.0);
        let (l, c) = (linear, centre);
        let points = self
            .points
            .iter()
            .map(|p| {
                let q = l.transform_vector(&Vector3::new(p[0] as f64 - c[0], p[1] as f64 - c[1], p[2] as f64 - c[2]));
                [q.x as f32, q.y as f32, q.z as f32]
            })
            .collect();
        PointCloud::with_origin(points, [landed.x, landed.y, landed.z])
    }

    /// [`PointCloud::transformed`], mapping the points where they are: the same cloud, bit for
    /// bit, without a second copy of a large one.
    pub fn into_transformed(mut self, m: &Matrix4<f64>) -> PointCloud {
        let (map, origin) = self.mapping(m);
        let apply = crate::transform::mapping(&map);
        for p in &mut self.points {
            *p = apply(*p);
        }
        self.origin = origin;
        self
    }

    /// What [`PointCloud::transformed`] maps the offsets by, and the new origin.
    fn mapping(&self, m: &Matrix4<f64>) -> (Matrix4<f64>, [f64; 3]) {
        if self.origin_is_zero() {
            return (*m, [0.0; 3]);
        }
        let o = m.transform_point(&nalgebra::Point3::from(self.origin));
        let mut linear = *m;
        linear.fixed_view_mut::<3, 1>(0, 3).fill(0.0);
        (linear, [o.x, o.y, o.z])
    }

    /// The same points with origin zero: the offsets, taken as points in their own frame.
    pub fn into_local(self) -> PointCloud {
        PointCloud::new(self.points)
    }
}

impl From<Vec<[f32; 3]>> for PointCloud {
    /// [`PointCloud::new`]: the points as they are, origin zero (give coordinates far from zero
    /// as `f64`: `From<&[[f64; 3]]>`).
    fn from(points: Vec<[f32; 3]>) -> Self {
        PointCloud::new(points)
    }
}

impl From<&[[f64; 3]]> for PointCloud {
    /// [`PointCloud::from_points_f64`]: offsets from an origin near the points when they lie far
    /// from zero, so they keep their digits.
    fn from(points: &[[f64; 3]]) -> Self {
        PointCloud::from_points_f64(points)
    }
}

/// Widens the box `[lo, hi]` to hold `p`, axis by axis; a NaN coordinate leaves that axis as it
/// was. Comparisons, not `f32::min`/`max`: those ignore NaN, which wasm's `f32.min` does not, so
/// in wasm they are a call per coordinate.
#[inline(always)]
pub(crate) fn grow_box<T: PartialOrd + Copy>(lo: &mut [T; 3], hi: &mut [T; 3], p: &[T; 3]) {
    for a in 0..3 {
        if p[a] < lo[a] {
            lo[a] = p[a];
        }
        if p[a] > hi[a] {
            hi[a] = p[a];
        }
    }
}

/// Largest half-extent for which [`PointCloud::from_points_f64`] recentres: beyond it the
/// offsets would not fit `f32` (whose largest value is 3.4e38) and finite points would become
/// infinite, so such a cloud keeps origin zero (its points beyond `f32`'s range are infinite as
/// they would be anyway).
const MAX_OFFSET: f64 = 1e37;

/// Points of the even sample that [`choose_origin`] takes its median and spread from.
const ORIGIN_SAMPLE: usize = 4096;

/// How far from the bulk of a cloud, in spreads, a point is a stray that [`PointCloud::from_points_f64`] leaves
/// out of the box it centres on: the spread is half the distance between the 10th and the 90th
/// percentile of a sample, the largest over the axes. A stray return, or a point written as
/// (0, 0, 0) in a survey of map-grid coordinates, would otherwise pull the box's centre away from
/// every other point, and their offsets from it would lose their digits in `f32`.
pub const STRAY_SPREADS: f64 = 64.0;

/// The origin [`PointCloud::from_points_f64`] picks for the `n` points `point(i)`: the
/// bounding-box centre of its bulk, when that centre is more than [`RECENTER_RATIO`] times the
/// bulk's half-extent from zero (and the whole cloud's half-extent fits `f32`), else zero. The
/// bulk: the points finite in `f32` within [`STRAY_SPREADS`] spreads of the median of an even
/// sample (every such point, in a cloud without strays).
fn choose_origin(n: usize, point: impl Fn(usize) -> [f64; 3]) -> [f64; 3] {
    // the points that are finite as f32 (a coordinate beyond f32's range is infinite either way)
    let usable = |p: &[f64; 3]| p.iter().all(|v| v.abs() <= f32::MAX as f64);
    let step = n.div_ceil(ORIGIN_SAMPLE).max(1);
    let sample: Vec<[f64; 3]> = (0..n).step_by(step).map(&point).filter(usable).collect();
    if sample.is_empty() {
        return [0.0; 3];
    }
    let mut median = [0.0; 3];
    let mut spread = 0.0f64;
    for a in 0..3 {
        let mut v: Vec<f64> = sample.iter().map(|p| p[a]).collect();
        v.sort_unstable_by(f64::total_cmp);
        let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
        median[a] = at(0.5);
        spread = spread.max((at(0.9) - at(0.1)) * 0.5);
    }
    // (a cloud whose sample sits on one point: every point within a tiny reach of it is bulk)
    let reach = STRAY_SPREADS * spread.max(median.iter().fold(0.0f64, |m, c| m.max(c.abs())) * 1e-9);
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let (mut all_lo, mut all_hi) = (lo, hi);
    for i in 0..n {
        let p = point(i);
        if !usable(&p) {
            continue;
        }
        grow_box(&mut all_lo, &mut all_hi, &p);
        if (0..3).all(|a| (p[a] - median[a]).abs() <= reach) {
            grow_box(&mut lo, &mut hi, &p);
        }
    }
    if !lo[0].is_finite() {
        return [0.0; 3];
    }
    let center = [0, 1, 2].map(|a| lo[a] * 0.5 + hi[a] * 0.5);
    let half = (0..3).map(|a| (hi[a] - lo[a]) * 0.5).fold(0.0, f64::max);
    let whole = (0..3).map(|a| (all_hi[a] - all_lo[a]) * 0.5).fold(0.0, f64::max);
    let far = center.iter().fold(0.0f64, |m, c| m.max(c.abs()));
    // offsets from the centre are at most the whole cloud's extent: recentring needs them to fit f32
    if far > RECENTER_RATIO * half && whole < MAX_OFFSET {
        center
    } else {
        [0.0; 3]
    }
}

/// The mean of `points`, accumulated in `f64` (the origin for none).
pub(crate) fn centroid_of(points: &[[f32; 3]]) -> [f64; 3] {
    let mut s = [0.0f64; 3];
    for p in points {
        for a in 0..3 {
            s[a] += p[a] as f64;
        }
    }
    let n = points.len().max(1) as f64;
    [s[0] / n, s[1] / n, s[2] / n]
}

/// The largest half-extent of the box `[lo, hi]`.
pub(crate) fn half_extent_of(lo: [f32; 3], hi: [f32; 3]) -> f64 {
    (0..3).map(|a| (hi[a] as f64 - lo[a] as f64) * 0.5).fold(0.0, f64::max)
}

/// The normalisation the library applies before the network (docs/design.md §3).
///
/// **Rule**: each cloud is centred on its own bounding-box centre, and both are divided by one
/// shared scale `s` = the largest half-extent over both clouds' boxes, so each lies in
/// `[-1, 1]^3` with its aspect ratio kept. Because the scale is shared, a rigid
/// `T_target_source` in normalised units maps back to a rigid transform in user units:
/// `T_user = N_target^-1 * T_norm * N_source`, where `N(x) = (x - c) / s`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointNormalization {
    /// Bounding-box centre of the source, user units.
    pub source_center: [f64; 3],
    /// Bounding-box centre of the target, user units.
    pub target_center: [f64; 3],
    /// The shared scale (user units per normalised unit); always > 0.
    pub scale: f64,
}

impl JointNormalization {
    /// Computes the normalisation of a (validated) pair, from their `points` (the offsets from
    /// their origins: the pipeline normalises each cloud's local frame).
    pub fn of_pair(source: &PointCloud, target: &PointCloud) -> Self {
        Self::of_boxes(Self::box_of(source), Self::box_of(target))
    }

    /// A cloud's bounding-box centre and largest half-extent (relative to its origin): what
    /// [`JointNormalization::of_pair`] takes of each cloud.
    pub fn box_of(cloud: &PointCloud) -> ([f64; 3], f64) {
        let (lo, hi) = cloud.bounds();
        let center = [0, 1, 2].map(|a| (lo[a] as f64 + hi[a] as f64) * 0.5);
        (center, half_extent_of(lo, hi))
    }

    /// [`JointNormalization::of_pair`] from each cloud's [`JointNormalization::box_of`].
    pub fn of_boxes(source: ([f64; 3], f64), target: ([f64; 3], f64)) -> Self {
        let ((source_center, hs), (target_center, ht)) = (source, target);
        let scale = hs.max(ht);
        let scale = if scale > 0.0 && scale.is_finite() { scale } else { 1.0 };
        Self { source_center, target_center, scale }
    }

    /// `N_source`: user source units to normalised units.
    pub fn source_to_normalized(&self) -> Matrix4<f64> {
        Self::to_normalized(self.source_center, self.scale)
    }

    /// `N_target`: user target units to normalised units.
    pub fn target_to_normalized(&self) -> Matrix4<f64> {
        Self::to_normalized(self.target_center, self.scale)
    }

    fn to_normalized(center: [f64; 3], scale: f64) -> Matrix4<f64> {
        let inv = 1.0 / scale;
        let mut m = Matrix4::identity() * inv;
        m[(3, 3)] = 1.0;
        let c = Vector3::from(center) * inv;
        m.fixed_view_mut::<3, 1>(0, 3).copy_from(&(-c));
        m
    }

    /// Maps a normalised-units `T_target_source` back to user units.
    pub fn denormalize(&self, t_norm: &Matrix4<f64>) -> Matrix4<f64> {
        let nt = self.target_to_normalized();
        let nt_inv = nt.try_inverse().unwrap_or_else(Matrix4::identity);
        nt_inv * t_norm * self.source_to_normalized()
    }

    /// Maps a user-units `T_target_source` into normalised units.
    pub fn normalize_transform(&self, t_user: &Matrix4<f64>) -> Matrix4<f64> {
        let ns_inv = self.source_to_normalized().try_inverse().unwrap_or_else(Matrix4::identity);
        self.target_to_normalized() * t_user * ns_inv
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transform::{check_rigid, euler_xyz, from_rotation_translation};

    fn cube(n: usize) -> PointCloud {
        PointCloud::new((0..n).map(|i| [(i % 7) as f32, (i % 5) as f32 * 2.0, (i % 3) as f32 * 0.5]).collect())
    }

    #[test]
    fn packed_length_must_be_multiple_of_three() {
        assert!(PointCloud::from_xyz(&[0.0; 7]).is_err());
        assert_eq!(PointCloud::from_xyz(&[1.0, 2.0, 3.0]).unwrap().points, vec![[1.0, 2.0, 3.0]]);
    }

    #[test]
    fn validation_names_first_bad_index_or_drops() {
        let mut c = cube(40);
        c.points[17][1] = f32::NAN;
        c.points[30][0] = f32::INFINITY;
        let err = c.validated("source", MIN_POINTS, NonFinite::Error).unwrap_err().to_string();
        assert!(err.contains("source point 17"), "{err}");
        assert_eq!(c.validated("source", MIN_POINTS, NonFinite::Drop).unwrap().len(), 38);
        let err = cube(5).validated("target", MIN_POINTS, NonFinite::Error).unwrap_err().to_string();
        assert!(err.contains("target has 5 finite points"), "{err}");
        let same = PointCloud::new(vec![[1.0, 1.0, 1.0]; 30]);
        assert!(same.validated("source", MIN_POINTS, NonFinite::Error).is_err());
        assert!(PointCloud::default().validated("source", MIN_POINTS, NonFinite::Error).is_err());
    }

    #[test]
    fn origins_carry_large_coordinates_through_transforms_and_validation() {
        let far: Vec<[f64; 3]> =
            (0..40).map(|i| [5e6 + (i % 7) as f64 * 0.01, 4e6 + (i % 5) as f64 * 0.02, 0.5]).collect();
        let c = PointCloud::from_points_f64(&far);
        assert!(!c.origin_is_zero());
        assert!((0..40).all(|i| (0..3).all(|a| (c.point_f64(i)[a] - far[i][a]).abs() < 1e-6)));
        let m = from_rotation_translation(&euler_xyz(0.3, -0.1, 0.2), &Vector3::new(12.0, -3.0, 7.0));
        let moved = c.transformed(&m);
        for (i, p) in far.iter().enumerate() {
            let want = m.transform_point(&nalgebra::Point3::from(*p));
            let got = moved.point_f64(i);
            assert!((0..3).all(|a| (got[a] - want[a]).abs() < 1e-6), "{got:?} vs {want:?}");
        }
        // mapped in place: the same cloud, bit for bit, near zero and far from it
        for cloud in [c.clone(), cube(40)] {
            let (copy, owned) = (cloud.transformed(&m), cloud.clone().into_transformed(&m));
            assert_eq!((copy.origin, copy.points), (owned.origin, owned.points));
        }
        let mut bad = c.clone();
        bad.points[3][0] = f32::NAN;
        let kept = bad.validated("source", MIN_POINTS, NonFinite::Drop).unwrap();
        assert_eq!((kept.len(), kept.origin), (39, c.origin));
        assert_eq!(c.clone().into_local().origin, [0.0; 3]);
        // points beyond f32's range (infinite either way) do not pull the origin away from the rest
        let wild = PointCloud::from_points_f64(&[[5e6, 4e6, 1.0], [5e6, 4e6, 1.9e185], [5e6, -1.2e147, 1.0]]);
        assert_eq!(wild.origin, [5e6, 4e6, 1.0]);
        assert_eq!(wild.points[0], [0.0; 3]);
        assert!(wild.points[1][2] == f32::INFINITY && wild.points[2][1] == f32::NEG_INFINITY);
        // a stray point (a survey's (0, 0, 0), a return kilometres off) does not pull the origin away
        // from the rest: their offsets keep their digits
        let survey: Vec<[f64; 3]> = (0..300)
            .map(|i| {
                [512_345.0 + (i % 17) as f64 * 0.61, 4_123_456.0 + (i % 13) as f64 * 0.73, 87.0 + (i % 7) as f64 * 0.3]
            })
            .collect();
        for stray in [[0.0, 0.0, 0.0], [512_345.0, 4_123_456.0, 9e7], [-3e7, 4_123_456.0, 87.0]] {
            let mut points = survey.clone();
            points.insert(150, stray);
            let c = PointCloud::from_points_f64(&points);
            let (lo, hi) = (c.origin, [c.origin[0] - 512_345.0, c.origin[1] - 4_123_456.0, c.origin[2] - 87.0]);
            assert!(hi.iter().all(|d| (0.0..12.0).contains(d)), "origin {lo:?} for stray {stray:?}");
            for (i, p) in points.iter().enumerate().filter(|(i, _)| *i != 150) {
                assert!((0..3).all(|a| (c.point_f64(i)[a] - p[a]).abs() < 1e-5), "point {i}: {:?}", c.point_f64(i));
            }
            assert!((0..3).all(|a| (c.point_f64(150)[a] - stray[a]).abs() < 8.0), "the stray, as f32 holds it");
        }
        // placed: a cloud near zero placed on a map grid keeps its digits (an origin there); placed
        // nearby, it is transformed as it is
        let local = cube(40);
        let onto_map =
            from_rotation_translation(&euler_xyz(0.3, -0.1, 0.2), &Vector3::new(512_345.6, 4_123_456.7, 87.0));
        let placed = local.placed(&onto_map);
        assert!(!placed.origin_is_zero());
        for i in 0..local.len() {
            let want = onto_map.transform_point(&nalgebra::Point3::from(local.point_f64(i)));
            assert!((0..3).all(|a| (placed.point_f64(i)[a] - want[a]).abs() < 1e-6), "{:?}", placed.point_f64(i));
        }
        let nearby = from_rotation_translation(&euler_xyz(0.3, -0.1, 0.2), &Vector3::new(12.0, -3.0, 7.0));
        assert_eq!(local.placed(&nearby), local.transformed(&nearby));
        assert_eq!(c.placed(&onto_map), c.transformed(&onto_map), "an origin already: mapped in f64 as it is");
        // near zero, nothing changes: origin zero, the points as given
        let near = PointCloud::from_points_f64(&[[1.0, 2.0, 3.0], [1.5, 2.0, 3.0]]);
        assert_eq!((near.origin, near.points.clone()), ([0.0; 3], vec![[1.0, 2.0, 3.0], [1.5, 2.0, 3.0]]));
    }

    #[test]
    fn normalization_maps_into_unit_box_and_back() {
        let s = cube(100);
        let t_user = from_rotation_translation(&euler_xyz(0.2, 0.1, -0.3), &Vector3::new(5.0, -2.0, 1.0));
        let t = s.transformed(&t_user);
        let n = JointNormalization::of_pair(&s, &t);
        for (c, nm) in [(&s, n.source_to_normalized()), (&t, n.target_to_normalized())] {
            let (lo, hi) = c.transformed(&nm).bounds();
            assert!(lo.iter().chain(hi.iter()).all(|v| v.abs() <= 1.0 + 1e-5));
        }
        let t_norm = n.normalize_transform(&t_user);
        assert!(check_rigid(&t_norm, 1e-9).is_ok());
        assert!((n.denormalize(&t_norm) - t_user).abs().max() < 1e-9);
    }
}
