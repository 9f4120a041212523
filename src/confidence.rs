//! How sure the engine is of an answer: evidence that separates right from wrong alignments,
//! and a logistic model over it calibrated on validation pairs ([`confidence`]).
//!
//! Fitness at one tight distance is a poor verdict on partial, independently sampled, noisy
//! scans: right answers often score 0.15-0.30. The fitness *curve* says more (a right answer's
//! rises early and steeply), and so does the overlap measured both ways.
//!
//! A good fit is not enough either: on a symmetric or featureless shape other poses fit as well,
//! and an answer that is one of `k` equally good poses is right with a probability of about
//! `1 / k`, however well it fits. So the evidence also looks for such poses: the answer turned
//! about the principal axes of the moved source (and the diagonals between them), of the
//! target points it overlaps and, for a part of the target (a scan onto a model), of the whole
//! target through its centroid (by a quarter, a third and a fifth of a turn too about an axis the
//! source or the target is round about: a 3-, 4- or 5-fold symmetry), and along the motion its
//! point-to-plane fit constrains
//! least, each refined by a short ICP ([`Evidence::ambiguity`], [`Evidence::alternatives`]), and the
//! answer slid along that motion without refinement ([`Evidence::slide`]: a surface of revolution
//! turned about its axis, a plane shifted in itself). The confidence is low on such answers,
//! right or wrong.
//!
//! The probes are also a search: a probe pose that fits *better* than the answer ([`probe`],
//! [`Probed::better`]; typically the answer flipped about an axis of an elongated shape) is
//! refined by the pipeline like one more start.

use crate::icp::{GiveUp, IcpKind, IcpParams, IcpTarget, Partners};
use crate::refine::{coincide, even_sample, SCREEN_POINTS};
use crate::register::UP_TOLERANCE_DEG;
use crate::transform::rigid_inverse;
use crate::transform::{apply, from_rotation_translation, rotation_error_deg, translation_error};
use nalgebra::Matrix4;
use nalgebra::{Matrix3, Matrix6, Rotation3, SymmetricEigen, Vector3, Vector6};
use serde::{Deserialize, Serialize};

/// The evidence behind [`confidence`], measured on the (voxelised) clouds under the answer, in
/// multiples of a distance `d`: the final max correspondence distance, or the default one (0.025
/// of the clouds' largest half-extent, where the confidence is calibrated) when that is smaller,
/// so that a wider distance the caller chose does not make every pose look right.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
#[cfg_attr(feature = "ts", derive(ts_rs::TS), ts(rename = "RegistrationEvidence"))]
pub struct Evidence {
    /// Fraction of source points with a target point within `d` (the result's `fitness` when `d`
    /// is the final distance).
    pub fitness: f64,
    /// The same within `d / 2`.
    pub fitness_tight: f64,
    /// The same within `2 d`.
    pub fitness_loose: f64,
    /// The same within `4 d`.
    pub fitness_coarse: f64,
    /// Fraction of target points with a source point within `d` (overlap the other way).
    pub overlap_reverse: f64,
    /// Inlier RMSE at `d`, divided by `d` (0 without inliers).
    pub rmse_ratio: f64,
    /// How well the best *different* pose fits, as a fraction of the answer's fitness (at most
    /// 2): the answer turned 90 degrees both ways and 180 degrees about each principal axis of
    /// the moved source, 180 degrees about the four diagonals between those axes and about each
    /// principal axis of the target points it overlaps (all through the moved source's
    /// centroid), 180 degrees about each principal axis of the whole target through its centroid
    /// when the source covers a much smaller share of the target than the target of the source (a
    /// scan onto a model, which may fit as well on the model's other end), and 60 degrees both
    /// ways along the least constrained motion of [`Evidence::slide`] (when that slide is at least
    /// 0.3), each refined by a short ICP; 0 when every one fell back onto the answer (within 15
    /// degrees and 0.2 of the clouds' half-extent). Near 1 or above: the answer may fit and still
    /// not be unique.
    pub ambiguity: f64,
    /// How many distinct poses (more than 15 degrees apart, or putting the source's centre more
    /// than 0.2 of the clouds' half-extent apart: a repeating structure's next element) fit at
    /// least 0.9 as well as the answer, among those probes (and the answer turned a quarter, a
    /// third and a fifth about an axis the source, or for a part the whole target, is round
    /// about) or, when more, among the other answers the
    /// search refined (its stages' best answers and the probes' better poses): with `k`
    /// alternatives the answer is one of `k + 1` about equally good poses.
    pub alternatives: f64,
    /// Fitness after sliding the answer along the motion its point-to-plane fit constrains
    /// least (the weakest eigenvector of the fit's 6x6 information matrix, scaled to move the
    /// points 0.25 of the normalised half-extent on average), the better of both ways, as a
    /// fraction of the answer's fitness (at most 2). Near 1: the fit does not pin the pose down
    /// along that motion (a surface of revolution, a plane, a cylinder, a tunnel). At
    /// [`SLID_FREE`] or above the motion counts as free, as for [`Evidence::constraint`]: the
    /// confidence is at most 0.25, with a warning naming the motion.
    pub slide: f64,
    /// How firmly the fit pins down that least constrained motion: the weakest eigenvalue of the
    /// point-to-plane fit's 6x6 information matrix (normalised units, about the inliers' centroid)
    /// over the strongest, in [0, 1]; 1 when too few points pair up to measure it. Below
    /// [`UNPINNED_CONSTRAINT`] the shapes' surfaces leave that motion free (a surface of revolution
    /// turned about its axis, a straight pipe or extrusion slid along itself, a plane in itself):
    /// only where the clouds' edges fall holds the pose there, and the answer's confidence is at
    /// most 0.25, with a warning naming the motion. Not an input of the logistic model.
    #[serde(default = "one")]
    pub constraint: f64,
}

/// [`Evidence::constraint`]'s default: not measured.
fn one() -> f64 {
    1.0
}

/// [`Evidence::constraint`] below this: the fit leaves a motion free. On 300 validation pairs
/// (paper protocol, any pose, upright) the lowest of answers at confidence 0.5 or more was about
/// 0.0013 (the bottles, surfaces of revolution whose sampling noise pins them a little); partial
/// views of a turntable jar or vase 0.0002-0.0008, a well-shaped figurine 0.007 or more
/// (`BENCHMARK.md`, "Motions the fit leaves free").
pub const UNPINNED_CONSTRAINT: f64 = 1e-3;

/// [`Evidence::slide`] at or above this: the fit barely holds the answer along its least
/// constrained motion either (it keeps this share of the fit slid a quarter of the clouds'
/// half-size along it), which is then as free as below [`UNPINNED_CONSTRAINT`]: a tunnel scan on
/// a helical ramp slid 16 m along it kept 0.86 (its constraint 0.0056). On 300 validation pairs
/// and the real scans no answer at or above it was right at a confidence above 0.5, and five
/// wrong ones had 0.5 or more (`BENCHMARK.md`, "Motions the fit barely holds").
pub const SLID_FREE: f64 = 0.85;

/// The motion the fit pins down least ([`Evidence::constraint`]), in the target's normalised
/// frame: the screw of the information matrix's weakest eigenvector.
#[derive(Clone, Copy, Debug)]
pub struct FreeScrew {
    /// The turn per unit of the motion (zero for a pure slide).
    pub w: Vector3<f64>,
    /// The translation per unit, at `c`.
    pub shift: Vector3<f64>,
    /// The inliers' centroid the motion turns about.
    pub c: Vector3<f64>,
    /// [`Evidence::constraint`].
    pub constraint: f64,
    /// [`Evidence::slide`].
    pub slide: f64,
    /// Further motions the fit leaves free (the information matrix's next eigenvectors whose
    /// eigenvalues also lie below [`UNPINNED_CONSTRAINT`] of the strongest, weakest first:
    /// a pipe's slide beside its turn, a plane's two slides beside its turn), as the turn per unit
    /// and the translation per unit at `c`; only [`FreeScrew::describe`] names them.
    pub also: [Option<(Vector3<f64>, Vector3<f64>)>; 2],
}

/// One motion of a [`FreeScrew`] ([`FreeScrew::parts`]), in the target's normalised frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ScrewPart {
    /// A turn about the axis along the unit vector `axis` through the point `through` (the
    /// axis's point nearest the inliers' centroid).
    Turn {
        /// The axis's direction, a unit vector.
        axis: Vector3<f64>,
        /// Its point nearest the inliers' centroid.
        through: Vector3<f64>,
    },
    /// A slide along the unit vector `direction`; `at` is the inliers' centroid.
    Slide {
        /// The direction, a unit vector.
        direction: Vector3<f64>,
        /// The inliers' centroid.
        at: Vector3<f64>,
    },
}

impl FreeScrew {
    /// `t` moved `s` units along the motion, exactly: turned by `s |w|` about the axis (through
    /// `c + w x shift / |w|^2`) and moved `s` times the shift's part along it (the probes' screw
    /// moves are first order, which a turn of tens of degrees about an axis the inliers' centroid
    /// lies off would carry off the surface); a slide moves by `s shift`.
    pub fn moved(&self, s: f64, t: &Matrix4<f64>) -> Matrix4<f64> {
        let turn = self.w.norm_squared();
        if turn <= 1e-18 {
            return Matrix4::new_translation(&(self.shift * s)) * t;
        }
        let on_axis = self.axis_point(self.w, self.shift);
        let along = self.w * (self.w.dot(&self.shift) / turn);
        let r = match nalgebra::Unit::try_new(self.w * s, 1e-12) {
            Some(axis) => Rotation3::from_axis_angle(&axis, (self.w * s).norm()).into_inner(),
            None => Matrix3::identity(),
        };
        from_rotation_translation(&r, &(on_axis - r * on_axis + along * s)) * t
    }

    /// `t` moved along the motion to where it puts `points` (source points, up to 256 of them
    /// used) nearest, on average, to where `guess` puts them: what a guess says where the clouds
    /// cannot. Over one whole turn (a slide: 2 normalised units either way), in 720 steps, then to
    /// a tenth of a step.
    pub fn nearest(&self, t: &Matrix4<f64>, guess: &Matrix4<f64>, points: &[[f32; 3]]) -> Matrix4<f64> {
        let sample = even_sample(points, 256);
        let pairs: Vec<(Vector3<f64>, Vector3<f64>)> = sample
            .iter()
            .map(|&p| (Vector3::from(apply(t, p).map(f64::from)), Vector3::from(apply(guess, p).map(f64::from))))
            .collect();
        let cost = |s: f64| {
            let m = self.moved(s, &Matrix4::identity());
            pairs.iter().map(|(q, g)| (m.transform_point(&(*q).into()).coords - g).norm_squared()).sum::<f64>()
        };
        let turn = self.w.norm();
        let reach = if turn > 1e-9 { std::f64::consts::PI / turn } else { 2.0 / self.shift.norm().max(1e-12) };
        let steps = 720i64;
        let step = 2.0 * reach / steps as f64;
        let best = |from: f64, step: f64, n: i64| {
            (-n..=n).map(|k| from + k as f64 * step).fold((from, cost(from)), |b, s| {
                let c = cost(s);
                if c < b.1 {
                    (s, c)
                } else {
                    b
                }
            })
        };
        let (coarse, _) = best(0.0, step, steps / 2);
        let (fine, _) = best(coarse, step / 10.0, 10);
        self.moved(fine, t)
    }

    /// `t` moved along this motion and each of [`FreeScrew::also`] in turn ([`FreeScrew::nearest`]
    /// along each, three rounds) to where it puts `points` nearest where `guess` puts them: a
    /// plane's answer brought to the guess along its two slides and its turn, not along one.
    pub fn nearest_along_all(&self, t: &Matrix4<f64>, guess: &Matrix4<f64>, points: &[[f32; 3]]) -> Matrix4<f64> {
        let others = self.also.iter().flatten().map(|&(w, shift)| FreeScrew { w, shift, also: [None; 2], ..*self });
        let motions: Vec<FreeScrew> = std::iter::once(*self).chain(others).collect();
        let rounds = if motions.len() > 1 { 3 } else { 1 };
        (0..rounds).fold(*t, |t, _| motions.iter().fold(t, |t, m| m.nearest(&t, guess, points)))
    }

    /// The point of the axis of the turn `w` with the translation `shift` at `c` (this motion's,
    /// or one of [`FreeScrew::also`]) nearest the inliers' centroid: `c + w x shift / |w|^2`.
    fn axis_point(&self, w: Vector3<f64>, shift: Vector3<f64>) -> Vector3<f64> {
        self.c + w.cross(&shift) / w.norm_squared()
    }

    /// Says what the motion is, with points in the caller's frame by `place` (written to a
    /// thousandth of `unit`, a normalised unit in the caller's: map-grid coordinates keep the
    /// digits that place them) and directions as they are (the normalisation neither turns nor
    /// mirrors): a turn about an axis (through a point, along a direction) when it mostly turns
    /// the points, else a slide along a direction.
    pub fn describe(&self, place: &dyn Fn(Vector3<f64>) -> Vector3<f64>, unit: f64) -> String {
        let fmt = |v: Vector3<f64>| {
            format!("({}, {}, {})", crate::error::num(v.x), crate::error::num(v.y), crate::error::num(v.z))
        };
        let decimals = (-(unit * 1e-3).log10()).ceil().clamp(0.0, 12.0) as usize;
        let at = |v: Vector3<f64>| {
            let one = |x: f64| {
                let text = format!("{x:.decimals$}");
                let text = if text.contains('.') { text.trim_end_matches('0').trim_end_matches('.') } else { &text };
                if text == "-0" {
                    "0".to_string()
                } else {
                    text.to_string()
                }
            };
            format!("({}, {}, {})", one(v.x), one(v.y), one(v.z))
        };
        let round = |v: Vector3<f64>| v.map(|x| (x * 1000.0).round() / 1000.0);
        let mut all: Vec<String> = self
            .parts()
            .into_iter()
            .map(|part| match part {
                ScrewPart::Turn { axis, through } => {
                    format!("a turn about the axis along {} through {}", fmt(round(axis)), at(place(through)))
                }
                ScrewPart::Slide { direction, .. } => format!("a slide along {}", fmt(round(direction))),
            })
            .collect();
        match all.len() {
            1 => all.remove(0),
            _ => {
                let last = all.pop().unwrap_or_default();
                format!("{} and {last}", all.join(", "))
            }
        }
    }

    /// What each motion the fit leaves free is (this one, then each of [`FreeScrew::also`]), in
    /// the target's normalised frame: a turn about an axis when it mostly turns the points, else
    /// a slide.
    pub fn parts(&self) -> Vec<ScrewPart> {
        let one = |w: Vector3<f64>, shift: Vector3<f64>| {
            let turn = w.norm();
            // the points move by |w| times their distance from the axis, up to about 1 normalised
            // unit, against |shift| for the slide
            if turn >= shift.norm() {
                ScrewPart::Turn { axis: w / turn, through: self.axis_point(w, shift) }
            } else {
                ScrewPart::Slide { direction: shift.normalize(), at: self.c }
            }
        };
        std::iter::once((self.w, self.shift))
            .chain(self.also.iter().flatten().copied())
            .map(|(w, s)| one(w, s))
            .collect()
    }

    /// How many motions the fit leaves free: this one and [`FreeScrew::also`].
    pub fn count(&self) -> usize {
        1 + self.also.iter().flatten().count()
    }
}

/// Measures the [`Evidence`] of `T_target_source` (source points moved into the target frame):
/// `target` and `source_index` are the prepared clouds (the source's as an [`IcpTarget`] too,
/// for the reverse overlap), `source` the source points, `d` the final distance, `kind` the ICP
/// of the probes ([`IcpKind::Off`] probes with point-to-point). On clouds of more than
/// [`crate::refine::SCREEN_POINTS`] points it is measured on that many, evenly spread, and the
/// probes on [`PROBE_POINTS`], so its cost does not grow with the point count beyond the
/// kd-tree queries' logarithm. It uses the target's normals (computed on first use).
#[allow(non_snake_case)]
pub fn evidence(
    target: &IcpTarget,
    source_index: &IcpTarget,
    source: &[[f32; 3]],
    T_target_source: &Matrix4<f64>,
    d: f64,
    kind: IcpKind,
) -> Evidence {
    probe(target, source_index, source, T_target_source, d, kind, &Admissible::Any).evidence
}

/// [`evidence`] together with the poses its turned probes found: the best different one, when it
/// fits the probe points better than the answer does, and those that fit about as well.
#[derive(Clone, Debug)]
pub struct Probed {
    /// The evidence of the answer.
    pub evidence: Evidence,
    /// A pose (turned and briefly refined; `T_target_source`) that fits better than the answer
    /// ([`Evidence::ambiguity`] above 1): the answer is then not the best fit, and a search
    /// refines this pose as one more start.
    pub better: Option<Matrix4<f64>>,
    /// The distinct poses the probes found that fit at least 0.9 as well as the answer, as many
    /// as [`Evidence::alternatives`] counts (`T_target_source`, briefly refined on the probe
    /// points).
    pub alternatives: Vec<Matrix4<f64>>,
    /// The motion the fit pins down least, when it leaves it free ([`Evidence::constraint`] below
    /// [`UNPINNED_CONSTRAINT`], or [`Evidence::slide`] at least [`SLID_FREE`]).
    pub free: Option<FreeScrew>,
}

/// Which poses the probes may find: any, or only those that keep a shared up axis (the
/// registration's `up` option).
pub enum Admissible<'a> {
    /// Every pose.
    Any,
    /// Poses that keep a shared up axis, within [`UP_TOLERANCE_DEG`].
    Upright {
        /// The axis (target frame) the probes also turn the answer about (every 45 degrees), since
        /// the turns about other axes tilt it.
        up: Vector3<f64>,
        /// How far a pose tilts the source's up off the target's, degrees.
        tilt_deg: &'a dyn Fn(&Matrix4<f64>) -> f64,
    },
}

impl Admissible<'_> {
    /// Whether the pose `t` may be counted (with a shared up axis: tilted at most
    /// [`UP_TOLERANCE_DEG`]).
    pub fn admits(&self, t: &Matrix4<f64>) -> bool {
        match self {
            Admissible::Any => true,
            Admissible::Upright { tilt_deg, .. } => tilt_deg(t) <= UP_TOLERANCE_DEG,
        }
    }

    /// Whether a probe may start from `t`: tilted so far, its ICP would not come back upright.
    fn may_start(&self, t: &Matrix4<f64>) -> bool {
        match self {
            Admissible::Any => true,
            Admissible::Upright { tilt_deg, .. } => tilt_deg(t) <= PROBE_START_TILT_DEG,
        }
    }
}

/// With a shared up axis, the probes' turns about it, degrees (each through the wide stage).
const UP_TURNS: [f64; 7] = [45.0, 90.0, 135.0, 180.0, -135.0, -90.0, -45.0];

/// With a shared up axis, a probe turned about another axis starts only when it tilts the answer
/// by at most this many degrees (a principal axis near up): the others cannot end upright.
const PROBE_START_TILT_DEG: f64 = 45.0;

/// [`evidence`], and the better pose its probes found, if any ([`Probed`]), counting only the
/// probe poses that `admissible` admits (in [`Evidence::ambiguity`], [`Evidence::alternatives`] and
/// the better pose).
#[allow(non_snake_case)]
pub fn probe(
    target: &IcpTarget,
    source_index: &IcpTarget,
    source: &[[f32; 3]],
    T_target_source: &Matrix4<f64>,
    d: f64,
    kind: IcpKind,
    admissible: &Admissible,
) -> Probed {
    let source = even_sample(source, SCREEN_POINTS);
    let target_points = even_sample(target.points(), SCREEN_POINTS);
    // the evaluations of one point set warm-start each other's searches (same results)
    let mut partners = Partners::default();
    let (fitness, rmse) = target.evaluate_warm(&source, T_target_source, d, &mut partners);
    let mut f = |k: f64| target.evaluate_warm(&source, T_target_source, k * d, &mut partners).0;
    let overlap_reverse = source_index.evaluate(&target_points, &rigid_inverse(T_target_source), d).0;
    let probe = even_sample(&source, PROBE_POINTS);
    // the answer's fitness on the probe points, which both probes compare against
    let mut probe_partners = Partners::default();
    let base = target.evaluate_warm(&probe, T_target_source, d, &mut probe_partners).0;
    let (slide, screw, constraint, also) = slide(target, &probe, T_target_source, d, base);
    let free = screw
        .filter(|_| constraint < UNPINNED_CONSTRAINT || slide >= SLID_FREE)
        .map(|Screw { w, shift, c }| FreeScrew { w, shift, c, constraint, slide, also });
    let answer = AnswerOnProbe { fitness: base, partners: probe_partners };
    // turns along the least constrained motion only where sliding along it keeps much of the fit
    let screw = screw.filter(|_| slide >= SCREW_MIN_SLIDE);
    // the source covers a smaller share of the target than the target of the source: a part of
    // it (a scan onto a model), which may fit as well on the target's other end
    let part = overlap_reverse < PART_OVERLAP * fitness;
    let extra = screw_turns(screw, T_target_source);
    // the moved source's spreads on all its sample points: a round axis is told from sampling
    // noise better than on the probe points
    let shape = principal_axes_spreads(&source, T_target_source);
    let turned = turns(target, &probe, T_target_source, d, answer, kind, &extra, admissible, part, shape);
    let (ambiguity, alternatives) = (turned.best_ratio.min(2.0), turned.alternatives.len() as f64);
    let (fitness_tight, fitness_loose, fitness_coarse) = (f(0.5), f(2.0), f(4.0));
    let evidence = Evidence {
        fitness,
        fitness_tight,
        fitness_loose,
        fitness_coarse,
        overlap_reverse,
        rmse_ratio: if d > 0.0 { rmse / d } else { 0.0 },
        ambiguity,
        alternatives,
        slide,
        constraint,
    };
    let better = turned.best.filter(|_| turned.best_ratio > 1.0);
    Probed { evidence, better, alternatives: turned.alternatives, free }
}

/// The answer's reverse overlap ([`Evidence::overlap_reverse`]) below this fraction of its
/// fitness: the source is a part of the target (a scan onto a model, where the ratio grows with
/// the share of the model the scan covers: 0.3-0.6 for a crop of 40-60% of it, 0.64-0.81 for one
/// view of a whole part; between two partial views of one overlap it is 0.89 or more on 99% of
/// the validation pairs), and the probes also turn the answer about the target's own principal
/// axes through its centroid ([`turns`]; `BENCHMARK.md`, "A scan on the model's other end", "One
/// view of a symmetric part").
const PART_OVERLAP: f64 = 0.85;
/// A principal axis about which a cloud is round, the variances along the other two within this
/// fraction of each other (a rocket's fins, a square block, three spokes), may be an axis of a 3-,
/// 4- or 5-fold symmetry: the probes also turn the answer by [`ROUND_TURNS`] about such an axis of
/// the moved source and, when the source is a part of the target, of the whole target.
const ROUND_SPREAD: f64 = 0.1;
/// The turns about a round axis ([`ROUND_SPREAD`]), degrees: a quarter, a third and a fifth of a
/// turn both ways find the look-alikes of a 4-, 3- and 5-fold symmetry (the half turn is probed
/// on every axis already), so that the answer is counted one of four, three or five. They
/// count look-alikes only: a pose they find that fits better is not searched from
/// ([`Probed::better`]), nor does it raise [`Evidence::ambiguity`], since on such a shape a turn
/// fits better or worse by the noise of the scan alone.
const ROUND_TURNS: [f64; 6] = [90.0, -90.0, 120.0, -120.0, 72.0, -72.0];
/// Points of the probes ([`Evidence::ambiguity`], [`Evidence::slide`]).
pub const PROBE_POINTS: usize = 512;
/// A probe pose that ends within this many degrees of the answer, and within
/// [`SAME_POSE_SHIFT`] of its place, has fallen back onto it; two alternatives this close are one.
const SAME_POSE_DEGREES: f64 = 15.0;
/// How far apart (normalised units: the clouds' shared half-extent is 1) two poses within
/// [`SAME_POSE_DEGREES`] put the source's centre and still are one: the evaluation's recall
/// threshold. Farther, the same turn is another place (a facade's next window bay, the same
/// stretch of a corridor further on).
const SAME_POSE_SHIFT: f64 = 0.2;
/// The turns of the ambiguity probe, degrees, about each principal axis of the moved source.
const TURNS: [f64; 3] = [180.0, 90.0, -90.0];
/// An alternative fitting at least this fraction of the answer's fitness counts in
/// [`Evidence::alternatives`].
const ALTERNATIVE_FIT: f64 = 0.9;
/// Each probe's ICP: iterations at `4 d` (the half turns and the turns along the least
/// constrained motion only), at `2 d`, then at `d`.
const PROBE_ITERATIONS: u32 = 10;
/// A probe whose fitness after its `4 d` or `2 d` stage is below this fraction of the answer's
/// at that distance stops there: it cannot come near the answer's fit. (The `4 d` stage lets a
/// half turn whose axis is some degrees off the true one still reach that pose.)
const PROBE_CUT: f64 = 0.6;
/// Within those two stages, a probe still below this fraction of the answer's fitness (at the
/// stage's distance) after [`PROBE_GIVE_UP_AFTER`] iterations stops at once ([`GiveUp`]): such a
/// probe nearly always ends the stage below [`PROBE_CUT`] (`BENCHMARK.md`, "Probes that give up
/// early").
const PROBE_GIVE_UP: f64 = 0.4;
/// Iterations of a probe's `4 d` or `2 d` stage before [`PROBE_GIVE_UP`] applies.
const PROBE_GIVE_UP_AFTER: u32 = 3;
/// How far [`Evidence::slide`] moves the points, on average (normalised units).
const SLIDE_RMS: f64 = 0.25;

/// The answer on the probe points: its fitness at `d`, and the points' partners in that
/// evaluation (they warm-start the next).
struct AnswerOnProbe {
    fitness: f64,
    partners: Partners,
}

/// What the turned probes of [`turns`] found.
struct Turned {
    /// The best different pose's fitness over the answer's (0: none).
    best_ratio: f64,
    /// That pose.
    best: Option<Matrix4<f64>>,
    /// Distinct poses fitting at least [`ALTERNATIVE_FIT`] as well as the answer.
    alternatives: Vec<Matrix4<f64>>,
}

/// The turned probes of `t` on the probe points `sample` ([`Evidence::ambiguity`],
/// [`Evidence::alternatives`]): [`TURNS`] about each principal axis of the moved sample, a half
/// turn about each of the four diagonals between them, and a
/// half turn about each principal axis of the target points it overlaps (the target is another
/// view: its axes differ from the partial source's, and a flip about one of them is a common
/// wrong answer of elongated shapes), each through the moved sample's centroid; when the source
/// is a `part` of the target ([`PART_OVERLAP`]), a half turn about each principal axis of the
/// whole target through the target's centroid (a scan of one end of a symmetric model fits as
/// well on its other end); [`ROUND_TURNS`] about each round axis ([`ROUND_SPREAD`]) of the moved
/// source (its `shape`: centroid, axes and spreads on all its sample points) and, for a part, of
/// the whole target, which count look-alikes only; then the `extra` starts (the turns along the least constrained
/// motion, [`screw_turns`]). `answer` is `t` on `sample`. A probe that comes back onto the answer, or
/// onto where an earlier probe was after the same stage ([`coincide`]), stops there and counts
/// for nothing: it would end where that pose did. A probe that fits too little after its `4 d` or
/// `2 d` stage ([`PROBE_CUT`]), or early in it ([`PROBE_GIVE_UP`]), stops there too.
// the probe's inputs and the three kinds of extra knowledge it takes (its own turns, the shared
// up, whether the source is a part of the target)
#[allow(clippy::too_many_arguments)]
fn turns(
    target: &IcpTarget,
    sample: &[[f32; 3]],
    t: &Matrix4<f64>,
    d: f64,
    answer: AnswerOnProbe,
    kind: IcpKind,
    extra: &[Matrix4<f64>],
    admissible: &Admissible,
    part: bool,
    (source_c, source_axes, source_spreads): (Vector3<f64>, Matrix3<f64>, Vector3<f64>),
) -> Turned {
    let AnswerOnProbe { fitness: base, mut partners } = answer;
    let mut out = Turned { best_ratio: 0.0, best: None, alternatives: Vec::new() };
    let base_loose = target.evaluate_warm(sample, t, 2.0 * d, &mut partners).0;
    if base <= 0.0 || sample.len() < 3 {
        return out;
    }
    let (c, axes) = principal_axes(sample, t);
    // (degrees, axis, a point on the axis)
    let mut probes: Vec<(f64, Vector3<f64>, Vector3<f64>)> = Vec::with_capacity(19);
    for degrees in TURNS {
        probes.extend((0..3).map(|k| (degrees, axes.column(k).into_owned(), c)));
    }
    // a partial view's principal axes are only estimates of the shape's: half turns about the
    // four diagonals between them too (with the axes, the thirteen axes of a cube's turns)
    for signs in [[1.0, 1.0, 1.0], [1.0, 1.0, -1.0], [1.0, -1.0, 1.0], [-1.0, 1.0, 1.0]] {
        probes.push((180.0, axes * Vector3::from(signs), c));
    }
    if let Some(target_axes) = overlap_axes(target, sample, t, 2.0 * d) {
        probes.extend((0..3).map(|k| (180.0, target_axes.column(k).into_owned(), c)));
    }
    // the turns that count look-alikes only: about the round axes of the moved source (a whole
    // object of 3- or 5-fold symmetry) and, for a part, of the whole target
    let mut round_turns: Vec<(f64, Vector3<f64>, Vector3<f64>)> = Vec::new();
    let mut round_axes = |axes: &Matrix3<f64>, spreads: &Vector3<f64>, pivot: Vector3<f64>| {
        for k in 0..3 {
            let (a, b) = (spreads[(k + 1) % 3], spreads[(k + 2) % 3]);
            if (a - b).abs() <= ROUND_SPREAD * a.max(b) {
                round_turns.extend(ROUND_TURNS.map(|degrees| (degrees, axes.column(k).into_owned(), pivot)));
            }
        }
    };
    round_axes(&source_axes, &source_spreads, source_c);
    if part {
        let whole = even_sample(target.points(), PROBE_POINTS);
        let (tc, target_axes, target_spreads) = principal_axes_spreads(&whole, &Matrix4::identity());
        probes.extend((0..3).map(|k| (180.0, target_axes.column(k).into_owned(), tc)));
        round_axes(&target_axes, &target_spreads, tc);
    }
    // with a shared up axis, the turns about it (the others tilt the answer, and are not counted)
    let up_turns = match admissible {
        Admissible::Upright { up, .. } => UP_TURNS.map(|degrees| (degrees, *up, c)).to_vec(),
        Admissible::Any => Vec::new(),
    };
    let turn = |(degrees, axis, pivot): (f64, Vector3<f64>, Vector3<f64>)| {
        let axis = nalgebra::Unit::new_normalize(axis);
        let r = Rotation3::from_axis_angle(&axis, degrees.to_radians()).into_inner();
        from_rotation_translation(&r, &(pivot - r * pivot)) * t
    };
    // (start, whether it first goes through the wide stage, whether a better pose it finds is
    // searched from): the half turns, the screw turns and the round turns go through the wide
    // stage, since their axes are only estimates of the true one
    let starts: Vec<(Matrix4<f64>, bool, bool)> = probes
        .into_iter()
        .map(|p| (turn(p), p.0 == 180.0, true))
        .chain(up_turns.into_iter().map(|p| (turn(p), true, true)))
        .chain(extra.iter().map(|&m| (m, true, true)))
        .chain(round_turns.into_iter().map(|p| (turn(p), true, false)))
        .collect();
    // a stage's ICP at `factor * d`; where the answer's fitness there is `base_at` (> 0: the
    // stages that cut), a probe far below it gives up early
    let params = |factor: f64, base_at: f64| IcpParams {
        max_iterations: PROBE_ITERATIONS,
        give_up: (base_at > 0.0).then_some(GiveUp { after: PROBE_GIVE_UP_AFTER, below: PROBE_GIVE_UP * base_at }),
        ..IcpParams::new(kind.or_point(), factor * d)
    };
    let base_coarse = target.evaluate_warm(sample, t, 4.0 * d, &mut partners).0;
    // each earlier probe's pose after each stage (4d, 2d, d; `None`: not run)
    let mut paths: Vec<[Option<Matrix4<f64>>; 3]> = Vec::with_capacity(starts.len());
    // each stage stops the probe when it cannot come near the answer's fit at that distance
    let stages = [(4.0, base_coarse), (2.0, base_loose), (1.0, 0.0)];
    // a start tilted far off a shared up axis would end tilted, where it cannot count
    for (start, wide, searched) in starts.into_iter().filter(|(s, _, _)| admissible.may_start(s)) {
        // each probe's stages warm-start each other's searches
        let mut partners = Partners::default();
        let mut path = [None; 3];
        let mut at = start;
        // a probe that has come back onto the answer, or onto where an earlier probe was after
        // the same stage, would end where that one did: it is dropped (the answer's own pose is
        // skipped below anyway, and an earlier probe's end is already counted)
        let mut repeats = false;
        for (k, &(factor, base_at)) in stages.iter().enumerate().skip(if wide { 0 } else { 1 }) {
            let r = target.align_warm(sample, &at, &params(factor, base_at), &mut partners);
            at = r.T_target_source;
            repeats =
                coincide(&at, t, sample, d) || paths.iter().any(|p| p[k].is_some_and(|q| coincide(&at, &q, sample, d)));
            path[k] = Some(at);
            if repeats || r.fitness < PROBE_CUT * base_at {
                break;
            }
        }
        paths.push(path);
        if repeats {
            continue;
        }
        let alt = at;
        if same_pose(&alt, t) || !admissible.admits(&alt) {
            continue;
        }
        let ratio = target.evaluate_warm(sample, &alt, d, &mut partners).0 / base;
        if searched && ratio > out.best_ratio {
            out.best_ratio = ratio;
            out.best = Some(alt);
        }
        if ratio >= ALTERNATIVE_FIT {
            count_if_new(&mut out.alternatives, t, alt);
        }
    }
    out
}

/// Raises `e.alternatives` to the number of poses among `others` (refined answers of a search,
/// each `T_target_source` with its fitness) that fit at least 0.9 (`ALTERNATIVE_FIT`) as well as
/// the answer `T_target_source` (fitness `fitness`, measured like theirs) and are other poses
/// than it and than each other ([`same_pose`]), when that number is higher, and adds those poses
/// to `poses` (the probes' alternatives, [`Probed::alternatives`]) where they are other poses
/// than every pose there; none when the answer fits nothing
/// (`fitness` 0). The probes turn the answer about a few
/// axes; a search that refined starts from unrelated poses (global hypotheses, turned starts)
/// finds look-alikes about other axes too. The count stays the larger of the two sets' (what the
/// confidence was calibrated with); `poses` gathers every look-alike found.
#[allow(non_snake_case)]
pub fn count_search_alternatives(
    e: &mut Evidence,
    poses: &mut Vec<Matrix4<f64>>,
    T_target_source: &Matrix4<f64>,
    fitness: f64,
    others: &[(Matrix4<f64>, f64)],
) {
    // an answer that fits nothing has no look-alikes (every pose fits "as well" as it), as in
    // the probes
    if fitness <= 0.0 {
        return;
    }
    let mut distinct: Vec<Matrix4<f64>> = Vec::new();
    for (t, f) in others {
        if *f >= ALTERNATIVE_FIT * fitness {
            count_if_new(&mut distinct, T_target_source, *t);
        }
    }
    e.alternatives = e.alternatives.max(distinct.len() as f64);
    for t in distinct {
        count_if_new(poses, T_target_source, t);
    }
}

/// Whether the poses `a` and `b` (`T_target_source`, normalised units, so that the translation
/// is where the source's centre goes) are one as alternatives count them: at most 15 degrees
/// (`SAME_POSE_DEGREES`) apart, and putting the source's centre at most 0.2 (`SAME_POSE_SHIFT`)
/// apart.
pub fn same_pose(a: &Matrix4<f64>, b: &Matrix4<f64>) -> bool {
    rotation_error_deg(a, b) <= SAME_POSE_DEGREES && translation_error(a, b) <= SAME_POSE_SHIFT
}

/// Adds `pose` to the alternatives `counted` of the answer `T_target_source` when it is another
/// pose than the answer and than each pose counted already ([`same_pose`]).
#[allow(non_snake_case)]
fn count_if_new(counted: &mut Vec<Matrix4<f64>>, T_target_source: &Matrix4<f64>, pose: Matrix4<f64>) {
    let other = |a: &Matrix4<f64>| !same_pose(a, &pose);
    if other(T_target_source) && counted.iter().all(other) {
        counted.push(pose);
    }
}

/// The principal axes (columns) of the target points within `radius` of the sample moved by
/// `t`; `None` when fewer than three are.
fn overlap_axes(target: &IcpTarget, sample: &[[f32; 3]], t: &Matrix4<f64>, radius: f64) -> Option<Matrix3<f64>> {
    let points = target.points();
    let near: Vec<[f32; 3]> =
        sample.iter().filter_map(|&p| target.nearest_within(&apply(t, p), radius).map(|j| points[j])).collect();
    if near.len() < 3 {
        return None;
    }
    Some(principal_axes(&near, &Matrix4::identity()).1)
}

/// The centroid of `sample` moved by `t`, and its principal axes (the columns).
pub(crate) fn principal_axes(sample: &[[f32; 3]], t: &Matrix4<f64>) -> (Vector3<f64>, Matrix3<f64>) {
    let (c, axes, _) = principal_axes_spreads(sample, t);
    (c, axes)
}

/// [`principal_axes`] with the variance along each axis (the eigenvalues, in the axes' order).
fn principal_axes_spreads(sample: &[[f32; 3]], t: &Matrix4<f64>) -> (Vector3<f64>, Matrix3<f64>, Vector3<f64>) {
    let moved: Vec<Vector3<f64>> = sample.iter().map(|&p| Vector3::from(apply(t, p).map(|v| v as f64))).collect();
    let n = moved.len() as f64;
    let c = moved.iter().fold(Vector3::zeros(), |a, p| a + p) / n;
    let cov = moved.iter().fold(Matrix3::zeros(), |a, p| a + (p - c) * (p - c).transpose()) / n;
    let e = SymmetricEigen::new(cov);
    (c, e.eigenvectors, e.eigenvalues)
}

/// The least constrained motion of a fit: a screw about the axis `w` (radians per unit) with the
/// shift `shift` per unit, through `c`.
#[derive(Clone, Copy, Debug)]
struct Screw {
    w: Vector3<f64>,
    shift: Vector3<f64>,
    c: Vector3<f64>,
}

/// The pose `t` moved by `s` units of `screw`.
fn screw_move(screw: &Screw, s: f64, t: &Matrix4<f64>) -> Matrix4<f64> {
    let Screw { w, shift, c } = *screw;
    let r = match nalgebra::Unit::try_new(w * s, 1e-12) {
        Some(axis) => Rotation3::from_axis_angle(&axis, (w * s).norm()).into_inner(),
        None => Matrix3::identity(),
    };
    from_rotation_translation(&r, &(c - r * c + shift * s)) * t
}

/// The turns of [`screw_turns`] are probed only when [`Evidence::slide`] is at least this: where
/// sliding along the least constrained motion loses most of the fit, the fit pins that motion
/// down, and turning 60 degrees along it is one more arbitrary turn. At 0.5, scans of an implant
/// abutment (a tapered post whose one flat they missed; slides of 0.33-0.50) were 43-115 degrees
/// off at 0.997; at 0.3 they are flagged, and on 1,000 bench pairs one right answer more fell
/// below 0.5 and no verdict on a wrong one changed (`BENCHMARK.md`, "Three more users' trials").
const SCREW_MIN_SLIDE: f64 = 0.3;

/// Degrees that the slide probes turn the answer along its least constrained motion.
const SCREW_DEGREES: f64 = 60.0;

/// `t` turned [`SCREW_DEGREES`] both ways along `screw` (none without one, or when that motion
/// barely turns).
fn screw_turns(screw: Option<Screw>, t: &Matrix4<f64>) -> Vec<Matrix4<f64>> {
    let Some(screw) = screw else { return Vec::new() };
    let turn = screw.w.norm();
    if turn.is_nan() || turn <= 1e-6 {
        return Vec::new();
    }
    let s = SCREW_DEGREES.to_radians() / turn;
    [1.0, -1.0].iter().map(|sign| screw_move(&screw, sign * s, t)).collect()
}

/// [`Evidence::slide`] of `t` on the probe points `sample`, the least constrained motion it
/// slid along (`None` with too few inliers), [`Evidence::constraint`], and the next motions below
/// [`UNPINNED_CONSTRAINT`] ([`FreeScrew::also`]). `base` is the fitness of `t` on `sample` at `d`.
#[allow(clippy::type_complexity)]
fn slide(
    target: &IcpTarget,
    sample: &[[f32; 3]],
    t: &Matrix4<f64>,
    d: f64,
    base: f64,
) -> (f64, Option<Screw>, f64, [Option<(Vector3<f64>, Vector3<f64>)>; 2]) {
    if base <= 0.0 || sample.len() < 3 {
        return (0.0, None, 1.0, [None; 2]);
    }
    let moved: Vec<Vector3<f64>> = sample.iter().map(|&p| Vector3::from(apply(t, p).map(|v| v as f64))).collect();
    // the inliers at d with their target normals
    let pairs: Vec<(Vector3<f64>, Vector3<f64>)> = moved
        .iter()
        .filter_map(|p| {
            let j = target.nearest_within(&[p.x as f32, p.y as f32, p.z as f32], d)?;
            Some((*p, Vector3::from(target.normal(j).map(|v| v as f64))))
        })
        .collect();
    if pairs.len() < 6 {
        return (0.0, None, 1.0, [None; 2]);
    }
    let c = pairs.iter().fold(Vector3::zeros(), |a, p| a + p.0) / pairs.len() as f64;
    let mut info = Matrix6::<f64>::zeros();
    for (p, n) in &pairs {
        let a = (p - c).cross(n);
        let j = Vector6::new(a.x, a.y, a.z, n.x, n.y, n.z);
        info += j * j.transpose();
    }
    let eig = SymmetricEigen::new(info);
    let weakest = eig.eigenvalues.imin();
    let strongest = eig.eigenvalues.max();
    let constraint = if strongest > 0.0 { (eig.eigenvalues[weakest] / strongest).clamp(0.0, 1.0) } else { 1.0 };
    let motion = |k: usize| {
        let v = eig.eigenvectors.column(k);
        (Vector3::new(v[0], v[1], v[2]), Vector3::new(v[3], v[4], v[5]))
    };
    let (w, shift) = motion(weakest);
    // the next eigenvectors below the free-motion line too, weakest first (a pipe, a plane)
    let mut next: [Option<usize>; 2] = [None; 2];
    for k in (0..6).filter(|&k| k != weakest && strongest > 0.0 && eig.eigenvalues[k] / strongest < UNPINNED_CONSTRAINT)
    {
        let below = |j: Option<usize>| j.is_none_or(|j| eig.eigenvalues[k] < eig.eigenvalues[j]);
        if below(next[0]) {
            next = [Some(k), next[0]];
        } else if below(next[1]) {
            next[1] = Some(k);
        }
    }
    let also = next.map(|k| k.map(motion));
    // the points' RMS displacement per unit of that motion
    let rms =
        (moved.iter().map(|p| (w.cross(&(p - c)) + shift).norm_squared()).sum::<f64>() / moved.len() as f64).sqrt();
    let screw = Screw { w, shift, c };
    if rms.is_nan() || rms <= 0.0 {
        return (0.0, None, constraint, also);
    }
    let mut best = 0.0f64;
    for sign in [1.0, -1.0] {
        let m = screw_move(&screw, sign * SLIDE_RMS / rms, t);
        best = best.max(target.evaluate(sample, &m, d).0 / base);
    }
    (best.min(2.0), Some(screw), constraint, also)
}

/// The model's inputs: the evidence, plus how steeply the fitness curve rises (tight over coarse).
fn features(e: &Evidence) -> [f64; 10] {
    let rise = if e.fitness_coarse > 0.0 { e.fitness_tight / e.fitness_coarse } else { 0.0 };
    [
        e.fitness,
        e.fitness_tight,
        e.fitness_loose,
        e.fitness_coarse,
        e.overlap_reverse,
        e.rmse_ratio,
        rise,
        e.ambiguity,
        e.alternatives,
        e.slide,
    ]
}

/// Logistic-regression weights of [`features`] and the bias (last), fitted by
/// `scripts/fit-confidence.py` on 2,400 answers: network + ICP, FPFH + RANSAC + ICP and the
/// exhaustive search on 500 paper-protocol and 300 any-pose validation pairs (`BENCHMARK.md`,
/// "Confidence", where the cross-validated figures are).
const WEIGHTS: [f64; 11] = [1.977, 0.5273, 1.661, -0.2899, 2.178, -0.334, 0.7324, -4.187, -0.5047, -1.748, 4.049];

/// The coarse fitness ([`Evidence::fitness_coarse`], within 4 `d`) from which the logistic model
/// is trusted: the right answers it was fitted and checked on all lie above it (the lowest of
/// about 6,000 on the validation sets was 0.39; on the real scans 0.54). Below it the
/// confidence is capped in proportion.
pub const SUPPORTED_COARSE_FITNESS: f64 = 0.4;

/// The probability that the answer is right (within the evaluation's recall thresholds: rotation
/// error below 15 degrees and translation error below 0.2 of the normalised half-extent), in
/// [0, 1]: a logistic model over the [`Evidence`], calibrated on validation pairs, and at most
/// `1 / (1 + alternatives)`: an answer that is one of `k` poses fitting about as well is right
/// with a probability of about `1 / k` at best. So it is low when the clouds overlap poorly under
/// the answer, and also when other poses fit about as well (a symmetric or featureless shape):
/// then the answer may be right, but nothing in the clouds says so. Below 0.5, or with an
/// alternative (at most 0.5), the result carries a warning. It is also at most
/// `fitness_coarse /` [`SUPPORTED_COARSE_FITNESS`]: an answer under which few source points come
/// near the target at all has nothing in the clouds behind it, whatever the probes say (they
/// find nothing better, so `ambiguity` and `slide` are 0, values the model reads as a unique
/// fit). No overlap at all (fitness 0) and non-finite evidence give 0.
pub fn confidence(e: &Evidence) -> f64 {
    // no source point near the target: nothing in the clouds supports the answer
    if e.fitness.is_nan() || e.fitness <= 0.0 {
        return 0.0;
    }
    let x = features(e);
    let z: f64 = x.iter().zip(WEIGHTS.iter()).map(|(a, w)| a * w).sum::<f64>() + WEIGHTS[x.len()];
    let support = (e.fitness_coarse / SUPPORTED_COARSE_FITNESS).min(1.0);
    let cap = (1.0 / (1.0 + e.alternatives.max(0.0))).min(support);
    if z.is_finite() && cap.is_finite() {
        (1.0 / (1.0 + (-z).exp())).min(cap)
    } else {
        0.0
    }
}
