//! Support planes: the table or floor a scanned object stands on, which registration leaves out
//! ([`Support::Drop`], the default).
//!
//! A phone or depth-camera capture of an object takes in the surface under it. Registered onto a
//! model of the object alone, that plane spoils every stage: the bounding box, and with it the
//! normalisation the network sees, takes the table's size; the descriptors match the table to
//! the model's flat faces; ICP pulls the model's bottom onto it. Between two scans of an object
//! on a table, the tables disagree with the object's motion whenever the object was tipped or
//! turned over between them (`BENCHMARK.md`, "A support plane under the scan").
//!
//! The test looks at an even sample of the cloud ([`Spacing`]: at most [`crate::spacing::SAMPLE`]
//! points). Each of [`SEEDS`] sample points spread over it proposes the plane of its [`NEIGHBOURS`]
//! nearest sample points when they are flat, and counts the sample points within a band about it
//! ([`THICKNESS`] median neighbour distances, or more for a noisier plane). The [`MAX_PLANES`] most
//! populous distinct planes are refitted to their points and tested in that order; the first that
//! passes is the support:
//! - at least [`MIN_SHARE`] of the sample lies on it and [`MIN_REST`] off it (an object stands
//!   on it: a cloud that is nearly all one plane is a flat object or a wall), or
//!   [`MIN_REST_PAIRED`] where the other cloud of the pair stands on a support by either share
//!   ([`find_paired`]: views that are nearly all table, or turntable, around a small object);
//! - all but [`OTHER_SIDE`] of the points off it lie on one side (the object stands on it; a
//!   plane through the middle of a shape is part of the shape), strays aside ([`STRAY_REACH`]:
//!   they neither count here nor widen the footprint below);
//! - at least [`BEYOND`] of its points lie outside the footprint of the points off it (their
//!   bounding rectangle in the plane), at least [`SIDE_SHARE`] of them beyond each of at least
//!   [`SIDES`] of its sides: it reaches out beyond what stands on it, as a table does, and as a
//!   box's bottom face, the floor of a room between its walls or the ground of a street do not;
//! - it is one layer, not a face of a sheet (a panel's model, both faces sampled): at least
//!   [`MIDDLE_SHARE`] of its points lie near its middle ([`MIDDLE`]), where a table's points
//!   gather, as one layer with noise does, while two faces within its band lie in two layers with
//!   hardly a point between; and fewer than [`SECOND_LAYER`] as many sample points lie just beside
//!   its band (within twice it), where a sheet's other face lies and only the rim of what stands
//!   on a table does.
//!
//! The points of the whole cloud within the plane's fitted thickness are its points, with those
//! under it (nothing stands below a support) and those of its noise's tail above it (up to twice
//! its band) outside the footprint of what stands on it: left in, a few of those at the table's
//! edges would stretch the cloud's box, and with it the default distance, to the table's size.

use crate::cloud::MIN_POINTS;
use crate::spacing::Spacing;
use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use serde::{Deserialize, Serialize};

/// What registration does with a support plane, the table or floor under a scanned object
/// (`Options::support_plane`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
#[cfg_attr(feature = "ts", derive(ts_rs::TS), ts(rename = "SupportPlane"))]
pub enum Support {
    /// Leave it out of each cloud that stands on one, with a warning that says how many points
    /// it held (the default).
    #[default]
    Drop,
    /// Keep every point: for two scans of an object that stood still on the table between them,
    /// where the shared table helps.
    Keep,
}

/// Fewest sample points the test needs.
pub const MIN_SAMPLE: usize = 64;

/// Sample points, spread evenly over the sample, that each propose a plane.
pub const SEEDS: usize = 128;

/// The nearest sample points whose plane a seed proposes.
pub const NEIGHBOURS: usize = 32;

/// A seed proposes a plane only when its neighbours' smallest principal spread is at most this
/// share of their middle one (they lie on a plane, not on a curve or an edge).
pub const FLATNESS: f64 = 0.05;

/// Most distinct planes tested, the most populous first.
pub const MAX_PLANES: usize = 4;

/// Two seeds' planes are the same plane when their normals are within about 10° and each
/// point lies within twice the band of the other.
const SAME_COS: f64 = 0.985;

/// Half the plane's thickness, in the sample's median distances to the 4th nearest sample point
/// (`outliers::reach`).
pub const THICKNESS: f32 = 0.3;

/// Least share of the sample on the plane.
pub const MIN_SHARE: f64 = 0.1;

/// Least share of the sample off the plane (more than twice its band away).
pub const MIN_REST: f64 = 0.1;

/// Least share of the sample off the plane when the other cloud of the pair stands on a support
/// plane by this share or [`MIN_REST`] ([`find_paired`]): a view that is nearly all table around
/// a small object, whose partner shows that the scene stands on one.
pub const MIN_REST_PAIRED: f64 = 0.01;

/// Most share of the points off the plane that may lie on its other side.
pub const OTHER_SIDE: f64 = 0.03;

/// A sample point whose reach ([`Spacing::reach`]) is more than this many times the sample's
/// median is a stray (a flying pixel at a depth edge, a stray return): the points off the plane
/// are judged without them, since an even sample keeps nearly every stray of a dense scan while
/// thinning its surfaces (0.2% of a phone capture's points scattered along its view rays put
/// more than [`OTHER_SIDE`] of the sample's off-plane points under its floor).
pub const STRAY_REACH: f32 = 3.0;

/// Least share of the plane's points outside the footprint of the points off it.
pub const BEYOND: f64 = 0.3;

/// Least share of the plane's points beyond a side of the footprint for the side to count.
pub const SIDE_SHARE: f64 = 0.05;

/// Fewest of the footprint's four sides the plane must reach beyond: a table seen around the
/// object, not the bottom of a shape whose walls were cut on one side.
pub const SIDES: usize = 3;

/// A plane's points near its middle: nearer it than this share of their median distance to it.
pub const MIDDLE: f64 = 0.25;

/// Least share of a plane's points near its middle ([`MIDDLE`]): one noisy layer has 13% there
/// (Gaussian noise; 12.5% uniform), the two faces of a sheet none.
pub const MIDDLE_SHARE: f64 = 0.04;

/// Most sample points just beside a plane's band (farther than the band, within twice it), as a
/// share of the plane's own: more is a second layer, the other face of a sheet.
pub const SECOND_LAYER: f64 = 0.5;

/// A support plane found in a cloud ([`find`]).
#[derive(Clone, Debug, PartialEq)]
pub struct SupportPlane {
    /// A point of the plane (the cloud's frame).
    pub point: [f64; 3],
    /// Its unit normal, towards the side the rest of the cloud stands on.
    pub normal: [f64; 3],
    /// Half its thickness: points nearer the plane are its points.
    pub half_thickness: f64,
    /// The indices (ascending) of the cloud's points on it.
    pub indices: Vec<usize>,
}

/// The centroid and the principal axes (columns, by ascending spread) of `points`, with the
/// spreads (variances).
fn principal(points: impl Iterator<Item = [f32; 3]> + Clone) -> Option<(Vector3<f64>, Matrix3<f64>, [f64; 3])> {
    let mut n = 0usize;
    let mut c = Vector3::zeros();
    for p in points.clone() {
        c += Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64);
        n += 1;
    }
    if n < 3 {
        return None;
    }
    c /= n as f64;
    let mut cov = Matrix3::zeros();
    for p in points {
        let d = Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64) - c;
        cov += d * d.transpose();
    }
    cov /= n as f64;
    let scale = cov.abs().max();
    if !(scale > 0.0 && scale.is_finite()) {
        return None;
    }
    let eig = SymmetricEigen::new(cov / scale);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let axes = Matrix3::from_columns(&order.map(|j| eig.eigenvectors.column(j).into_owned()));
    Some((c, axes, order.map(|j| eig.eigenvalues[j].max(0.0) * scale)))
}

/// A plane: a point on it and its unit normal.
#[derive(Clone, Copy, Debug)]
struct Plane {
    point: Vector3<f64>,
    normal: Vector3<f64>,
}

impl Plane {
    fn distance(&self, p: &[f32; 3]) -> f64 {
        self.distance_to(&Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64))
    }

    fn distance_to(&self, p: &Vector3<f64>) -> f64 {
        (p - self.point).dot(&self.normal)
    }
}

/// A seed's plane and the band it was counted in.
#[derive(Clone, Copy, Debug)]
struct Candidate {
    plane: Plane,
    band: f64,
    count: usize,
}

/// The support plane `points` stand on, if any (see the module docs).
pub fn find(points: &[[f32; 3]]) -> Option<SupportPlane> {
    find_with(points, &Spacing::of(points))
}

/// [`find`] with the sample of `points` already made (`spacing`, [`Spacing::of`] them).
pub fn find_with(points: &[[f32; 3]], spacing: &Spacing) -> Option<SupportPlane> {
    Planes::of(points, spacing)?.alone()
}

/// [`find_with`] for a cloud whose partner stands on a support plane (by either share): the
/// plane may hold all but [`MIN_REST_PAIRED`] of the sample (a table scanned around a small
/// object, which [`MIN_REST`] alone takes for a flat object or a wall).
pub fn find_paired(points: &[[f32; 3]], spacing: &Spacing) -> Option<SupportPlane> {
    Planes::of(points, spacing)?.paired()
}

/// A cloud's support plane, by the share that found it ([`Planes::stands`]).
#[derive(Clone, Debug, PartialEq)]
pub enum Stands {
    /// At least [`MIN_REST`] of the sample off it: a support whatever the other cloud.
    Alone(SupportPlane),
    /// Only [`MIN_REST_PAIRED`] off it: a support where the other cloud stands on one too.
    Paired(SupportPlane),
}

impl Stands {
    /// The plane to leave out: a plane found [`Stands::Alone`], or one found
    /// [`Stands::Paired`] where `partner` (the other cloud) stands on a support plane.
    pub fn plane(self, partner: bool) -> Option<SupportPlane> {
        match self {
            Stands::Alone(p) => Some(p),
            Stands::Paired(p) => partner.then_some(p),
        }
    }
}

/// The planes a cloud may stand on: the [`MAX_PLANES`] most populous distinct planes of its
/// sample, found once and tested by either share ([`Planes::alone`], [`Planes::paired`]).
pub struct Planes<'a> {
    points: &'a [[f32; 3]],
    sample: &'a [[f32; 3]],
    /// The sample points that stand among others (not strays), which judge the points off a plane.
    settled: Vec<[f32; 3]>,
    /// The sample's median reach.
    reach: f64,
    distinct: Vec<Candidate>,
}

impl<'a> Planes<'a> {
    /// The planes of `points` (their sample `spacing`); `None` for a sample of fewer than
    /// [`MIN_SAMPLE`] points or without a positive reach.
    pub fn of(points: &'a [[f32; 3]], spacing: &'a Spacing) -> Option<Self> {
        let Spacing { sample, index, .. } = spacing;
        if sample.len() < MIN_SAMPLE {
            return None;
        }
        let reach = spacing.median as f64;
        if !(reach > 0.0 && reach.is_finite()) {
            return None;
        }
        let mut out = Vec::with_capacity(NEIGHBOURS + 1);
        let count = |plane: &Plane, band: f64| sample.iter().filter(|p| plane.distance(p).abs() <= band).count();
        // the seeds' planes, each counted in a band of its own: the larger of THICKNESS times the
        // sample's median reach and three times the spread of the seed's neighbours about it (a
        // sparser, noisier table than the object on it)
        let seeds = SEEDS.min(sample.len());
        let mut candidates: Vec<Candidate> = Vec::with_capacity(seeds);
        for s in 0..seeds {
            let q = &sample[s * sample.len() / seeds];
            index.knn_into(q, NEIGHBOURS, &mut out);
            let Some((c, axes, spread)) = principal(out.iter().map(|&(i, _)| sample[i])) else { continue };
            if spread[0] > FLATNESS * spread[1] {
                continue;
            }
            let plane = Plane { point: c, normal: axes.column(0).into_owned() };
            let band = (THICKNESS as f64 * reach).max(3.0 * spread[0].sqrt());
            candidates.push(Candidate { plane, band, count: count(&plane, band) });
        }
        // the most populous first (stable: the first seed on ties), each distinct plane once
        candidates.sort_by_key(|c| std::cmp::Reverse(c.count));
        let mut distinct: Vec<Candidate> = Vec::with_capacity(MAX_PLANES);
        for c in candidates {
            if distinct.len() >= MAX_PLANES {
                break;
            }
            let same = |t: &Candidate| {
                t.plane.normal.dot(&c.plane.normal).abs() > SAME_COS
                    && t.plane.distance_to(&c.plane.point).abs() <= 2.0 * c.band
            };
            if !distinct.iter().any(same) {
                distinct.push(c);
            }
        }
        let settled: Vec<[f32; 3]> = spacing.settled(STRAY_REACH).copied().collect();
        Some(Planes { points, sample, settled, reach, distinct })
    }

    /// The support plane, with at least [`MIN_REST`] of the sample off it.
    pub fn alone(&self) -> Option<SupportPlane> {
        self.first(MIN_REST)
    }

    /// The support plane as the pair of a cloud that stands on one, with at least
    /// [`MIN_REST_PAIRED`] of the sample off it.
    pub fn paired(&self) -> Option<SupportPlane> {
        self.first(MIN_REST_PAIRED)
    }

    /// The plane found [`Planes::alone`], or else [`Planes::paired`].
    pub fn stands(&self) -> Option<Stands> {
        self.alone().map(Stands::Alone).or_else(|| self.paired().map(Stands::Paired))
    }

    /// The first of the planes, most populous first, that is a support with at least `min_rest`
    /// of the sample off it.
    fn first(&self, min_rest: f64) -> Option<SupportPlane> {
        self.distinct.iter().find_map(|c| test(self.points, self.sample, &self.settled, self.reach, min_rest, *c))
    }
}

/// `c`'s plane refitted, if it is a support of `points` (see the module docs) with at least
/// `min_rest` of the sample off it; `sample` is their even sample, `settled` those of its points
/// that are not strays ([`STRAY_REACH`]), and `reach` the sample's median reach.
fn test(
    points: &[[f32; 3]],
    sample: &[[f32; 3]],
    settled: &[[f32; 3]],
    reach: f64,
    min_rest: f64,
    c: Candidate,
) -> Option<SupportPlane> {
    let (mut plane, band) = (c.plane, c.band);
    // refit to the points in its band, twice
    for _ in 0..2 {
        let on = sample.iter().copied().filter(|p| plane.distance(p).abs() <= band);
        let (c, axes, _) = principal(on)?;
        plane = Plane { point: c, normal: axes.column(0).into_owned() };
    }
    let on: Vec<[f32; 3]> = sample.iter().copied().filter(|p| plane.distance(p).abs() <= band).collect();
    let off: Vec<(f64, [f32; 3])> =
        settled.iter().map(|p| (plane.distance(p), *p)).filter(|(d, _)| d.abs() > 2.0 * band).collect();
    let n = sample.len() as f64;
    if (on.len() as f64) < MIN_SHARE * n || (off.len() as f64) < min_rest * n {
        return None;
    }
    // a second layer just beside it: the other face of a sheet
    let beside = sample.iter().filter(|p| (band..=2.0 * band).contains(&plane.distance(p).abs())).count();
    if beside as f64 >= SECOND_LAYER * on.len() as f64 {
        return None;
    }
    // the rest on one side: the normal turned towards it
    let above = off.iter().filter(|(d, _)| *d > 0.0).count();
    let below = off.len() - above;
    if (above.min(below) as f64) > OTHER_SIDE * off.len() as f64 {
        return None;
    }
    if below > above {
        plane.normal = -plane.normal;
    }
    // the plane's points outside the footprint of the rest: in-plane axes from the plane's points
    let (_, axes, _) = principal(on.iter().copied())?;
    let (u, v) = (axes.column(2).into_owned(), axes.column(1).into_owned());
    let coords = |p: &[f32; 3]| {
        let d = Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64) - plane.point;
        (d.dot(&u), d.dot(&v))
    };
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for (_, p) in &off {
        let (a, b) = coords(p);
        lo = [lo[0].min(a), lo[1].min(b)];
        hi = [hi[0].max(a), hi[1].max(b)];
    }
    let (lo, hi) = (lo.map(|x| x - reach), hi.map(|x| x + reach));
    // which sides of the footprint a point in plane coordinates lies beyond
    let beyond_sides = |(a, b): (f64, f64)| [a < lo[0], a > hi[0], b < lo[1], b > hi[1]];
    let outside = |ab: (f64, f64)| beyond_sides(ab).iter().any(|&o| o);
    // how many of the plane's points lie beyond each side of the footprint, and beyond any
    let mut sides = [0usize; 4];
    let mut beyond = 0usize;
    for p in &on {
        let out = beyond_sides(coords(p));
        for (s, o) in sides.iter_mut().zip(out) {
            *s += o as usize;
        }
        beyond += out.iter().any(|&o| o) as usize;
    }
    let open_sides = sides.iter().filter(|&&s| s as f64 >= SIDE_SHARE * on.len() as f64).count();
    if (beyond as f64) < BEYOND * on.len() as f64 || open_sides < SIDES {
        return None;
    }
    // one layer, not a sheet's two faces: some of its points near its middle
    let mut residual: Vec<f64> = on.iter().map(|p| plane.distance(p).abs()).collect();
    let mad = crate::stats::median(&mut residual)?;
    let middle = residual.iter().filter(|&&r| r < MIDDLE * mad).count();
    if (middle as f64) < MIDDLE_SHARE * on.len() as f64 {
        return None;
    }
    // the thickness from the spread of the plane's sample points about it (scanner noise), at
    // most the band it was found in
    let half_thickness = (4.0 * 1.4826 * mad).clamp(0.25 * band, band);
    // its points: those within its thickness, those under it (its noise's far side, strays
    // under a floor: nothing stands below a support), and its noise's tail above it out of the
    // footprint of what stands on it (up to the height of the points off it), which would
    // otherwise stretch the cloud's box, and with it the default distance, to the table's edges
    let indices: Vec<usize> = (0..points.len())
        .filter(|&i| {
            let d = plane.distance(&points[i]);
            d <= half_thickness || (d <= 2.0 * band && outside(coords(&points[i])))
        })
        .collect();
    if points.len() - indices.len() < MIN_POINTS {
        return None;
    }
    Some(SupportPlane { point: plane.point.into(), normal: plane.normal.into(), half_thickness, indices })
}

/// The warning for a support plane of `dropped` points left out of the cloud `what` of `total`
/// points.
pub fn warning(what: &str, dropped: usize, total: usize) -> String {
    format!(
        "left out a plane of {dropped} of the {what}'s {total} points ({:.1}%) that the rest of it stands on (a table or floor under a scanned object); `supportPlane: \"keep\"` keeps it",
        100.0 * dropped as f64 / total.max(1) as f64
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloud::PointCloud;

    /// A deterministic stream in [-1, 1).
    fn stream(seed: u64) -> impl FnMut() -> f32 {
        let mut s = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
        move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
        }
    }

    /// `n` points on the surface of a box of half-sizes `h` standing on z = 0 (its bottom face
    /// left out when `bottom` is false), a little noisy.
    fn block(n: usize, h: [f32; 3], bottom: bool, seed: u64) -> Vec<[f32; 3]> {
        let mut r = stream(seed);
        let mut out = Vec::with_capacity(n);
        while out.len() < n {
            let (face, u, v, e) = (((r() + 1.0) * 3.0) as usize % 6, r(), r(), 0.002 * r());
            let p = match face {
                0 => [h[0] + e, u * h[1], (v + 1.0) * h[2]],
                1 => [-h[0] + e, u * h[1], (v + 1.0) * h[2]],
                2 => [u * h[0], h[1] + e, (v + 1.0) * h[2]],
                3 => [u * h[0], -h[1] + e, (v + 1.0) * h[2]],
                4 => [u * h[0], v * h[1], 2.0 * h[2] + e],
                _ if bottom => [u * h[0], v * h[1], e],
                _ => continue,
            };
            out.push(p);
        }
        out
    }

    /// `n` points on the level square of half-side `half` about the origin at z = 0, a little
    /// noisy.
    fn table(n: usize, half: f32, seed: u64) -> Vec<[f32; 3]> {
        let mut r = stream(seed);
        (0..n).map(|_| [r() * half, r() * half, 0.002 * r()]).collect()
    }

    #[test]
    fn a_table_under_an_object_is_found_and_the_object_kept() {
        let object = block(3_000, [0.3, 0.2, 0.25], false, 1);
        let mut points = object.clone();
        points.extend(table(1_500, 1.0, 2));
        let plane = find(&points).expect("a support plane");
        assert!(plane.normal[2] > 0.99, "{:?}", plane.normal);
        // every table point, and no object point above the plane's thickness
        assert!((3_000..4_500).all(|i| plane.indices.binary_search(&i).is_ok()));
        assert!(plane.indices.iter().all(|&i| i >= 3_000 || points[i][2] <= plane.half_thickness as f32 + 0.005));
        let kept = PointCloud::with_origin(points, [1.0, 2.0, 3.0]).without(&plane.indices);
        assert_eq!(kept.origin, [1.0, 2.0, 3.0]);
        assert!(kept.len() > 2_800 && kept.points.iter().all(|p| p[2] > 0.0));
    }

    #[test]
    fn the_tables_noise_tail_goes_with_it() {
        // a few of the table's points just beyond its thickness, above it and below it, out at
        // its edges: left in, they would stretch the object's box to the table's
        let mut points = block(3_000, [0.3, 0.2, 0.25], false, 23);
        points.extend(table(1_500, 1.0, 24));
        let ht = find(&points).expect("a support plane").half_thickness as f32;
        let mut r = stream(25);
        let tail: Vec<[f32; 3]> = (0..24)
            .map(|k| {
                let (x, y) = (r() * 0.3 + 0.65 * if k % 2 == 0 { 1.0 } else { -1.0 }, r());
                [x, y, if k % 3 == 0 { -1.5 * ht } else { 1.5 * ht }]
            })
            .collect();
        points.extend(tail);
        let plane = find(&points).expect("a support plane");
        assert!((3_000..points.len()).all(|i| plane.indices.binary_search(&i).is_ok()));
        let kept = PointCloud::with_origin(points.clone(), [0.0; 3]).without(&plane.indices);
        assert!(kept.len() > 2_800, "{}", kept.len());
        assert!(kept.points.iter().all(|p| p[0].abs() < 0.31 && p[1].abs() < 0.21), "the object's box");
        // the object's own walls near the table are kept: only what lies within the thickness goes
        assert!(plane.indices.iter().all(|&i| i >= 3_000 || points[i][2] <= plane.half_thickness as f32));
    }

    #[test]
    fn strays_under_the_table_do_not_hide_it() {
        // a depth camera's flying pixels: 1% of the points pushed 5-60 cm on along the view
        // rays from a camera above, some of them under the table
        let mut points = block(3_000, [0.3, 0.2, 0.25], false, 14);
        points.extend(table(1_500, 1.0, 15));
        let (camera, mut r) = (Vector3::new(0.0, -1.5, 1.5), stream(16));
        let strays: Vec<[f32; 3]> = (0..45)
            .map(|k| {
                let p = points[k * 97 % points.len()];
                let p = Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64);
                let q = p + (p - camera).normalize() * (0.325 + 0.275 * r() as f64);
                [q.x as f32, q.y as f32, q.z as f32]
            })
            .collect();
        assert!(strays.iter().filter(|p| p[2] < -0.05).count() >= 10);
        points.extend(strays);
        let plane = find(&points).expect("a support plane");
        assert!(plane.normal[2] > 0.99, "{:?}", plane.normal);
    }

    #[test]
    fn an_objects_own_faces_and_flat_clouds_are_not_supports() {
        // a closed box: its bottom face does not reach beyond its walls
        assert_eq!(find(&block(4_000, [0.3, 0.2, 0.25], true, 3)), None);
        // a flat cloud: nothing stands on it
        assert_eq!(find(&table(2_000, 1.0, 4)), None);
        // a plane through the middle of the object, reaching beyond it: points on both sides
        let mut points: Vec<[f32; 3]> =
            block(3_000, [0.3, 0.2, 0.25], true, 5).into_iter().map(|p| [p[0], p[1], p[2] - 0.25]).collect();
        points.extend(table(1_500, 1.0, 6));
        assert_eq!(find(&points), None);
        // a table beside the object on one side only (the floor of a cut-open shape)
        let mut points = block(3_000, [0.3, 0.2, 0.25], false, 7);
        points.extend(table(1_500, 1.0, 8).into_iter().map(|p| [p[0].abs() * 0.6 + 0.3, p[1] * 0.2, p[2]]));
        assert_eq!(find(&points), None);
    }

    #[test]
    fn a_sheet_with_both_faces_is_not_a_support() {
        // a thin panel's model (both faces, closer than the band) with a box standing on it: the
        // box on one face of a table would be dropped, but this plane is two layers
        let mut points = block(3_000, [0.3, 0.2, 0.25], false, 17);
        let mut top = table(1_500, 1.0, 18);
        top.iter_mut().for_each(|p| p[2] = -0.006 + p[2] * 0.1);
        points.extend(top);
        let mut bottom = table(1_500, 1.0, 19);
        bottom.iter_mut().for_each(|p| p[2] = -0.016 + p[2] * 0.1);
        let one_face = find(&points).expect("one face is a table");
        assert!(one_face.normal[2] > 0.99, "{:?}", one_face.normal);
        points.extend(bottom);
        assert_eq!(find(&points), None);
    }

    #[test]
    fn a_face_of_a_sheet_is_not_a_support() {
        // a box on a panel's model whose faces lie farther apart than the plane's band (0.01
        // here): its top face passes as a table until the bottom one lies just beside it
        let mut points = block(3_000, [0.3, 0.2, 0.25], false, 20);
        points.extend(table(1_500, 1.0, 21));
        let c = |points: &[[f32; 3]]| {
            let plane = Plane { point: Vector3::zeros(), normal: Vector3::z() };
            test(points, points, points, 0.05, MIN_REST, Candidate { plane, band: 0.01, count: 0 })
        };
        assert!(c(&points).is_some());
        points.extend(table(1_500, 1.0, 22).into_iter().map(|p| [p[0], p[1], -0.015 + p[2]]));
        assert_eq!(c(&points), None);
    }

    #[test]
    fn a_small_object_on_a_large_table_is_left_as_it_is_unless_its_pair_stands_on_one() {
        // too little stands off the plane (4% of the cloud): the object could be the plane's own
        let mut points = block(200, [0.1, 0.08, 0.1], false, 12);
        points.extend(table(4_800, 1.2, 13));
        let sample = Spacing::of(&points);
        assert_eq!(find_with(&points, &sample), None);
        // paired with a cloud that stands on a support, it is a table
        let plane = find_paired(&points, &sample).expect("a support plane");
        assert!(plane.normal[2] > 0.99 && (200..5_000).all(|i| plane.indices.binary_search(&i).is_ok()));
        // a table with nothing on it is none either way
        let bare = table(5_000, 1.2, 14);
        assert_eq!(find_paired(&bare, &Spacing::of(&bare)), None);
    }

    #[test]
    fn too_few_points_are_left_as_they_are() {
        let mut points = block(40, [0.3, 0.2, 0.25], false, 9);
        points.extend(table(20, 1.0, 10));
        assert_eq!(find(&points), None);
        assert_eq!(find(&[]), None);
    }
}
