// Generated from the Rust types by `scripts/gen-types.sh` (arps::contract::typescript);
// do not edit: change the Rust types and their docs, then run the script.

/**
 * Options of a registration (`Registrar::register` in Rust, `Registrar.register` in JS). Every
 * field has a default, given in its docs. In JS and JSON the fields are camelCase
 * (`networkPoints`, `icpMaxIterations`, ...; the conventions are in the `arps::contract` module
 * docs and `js/README.md`); every field may be left out (or be `null` in JS), which takes its
 * default; unknown fields, wrong types and out-of-range values are errors naming the field.
 */
export type RegisterOptions = {
  /**
   * Points per cloud fed to the network (each cloud is resampled to exactly this many; a
   * cloud with fewer points has some used twice, with a warning). Default: the model's N
   * (`ModelConfig.nPoints`, 128 for the default model). Range: the model's minimum
   * (`max(topH, 16)`) up to 4096 (`MAX_NETWORK_POINTS`; attention cost grows with its square).
   */
  networkPoints?: number | null,
  /**
   * Seed of every random choice (the network's point sampling, the global starts' RANSAC).
   * Default 0. The same inputs and seed give the same output, bit for bit, on a given build.
   * A non-negative integer (in JS a `bigint` from 2^53 on: a number that large may have been rounded).
   */
  seed?: number | bigint,
  /**
   * Refinement after the network: `"plane"` (point-to-plane ICP, target normals; the
   * default), `"point"` (point-to-point ICP) or `"off"` (the network + GMR estimate is the
   * answer). When both clouds are flat, `"plane"` runs point-to-point: every normal is the
   * plane's, and a point-to-plane fit could not move within it.
   */
  icp?: IcpKind,
  /**
   * Run the network. Default `true`. With `false` the coarse estimate is `initialTransform`
   * (the identity if unset) and only ICP runs: the classical baseline, or a refinement when a
   * good initial guess is known.
   */
  network?: boolean,
  /**
   * ICP's final maximum correspondence distance, in the clouds' units. Default: 2.5% of the
   * clouds' shared half-extent (of the points kept: far outliers and a dropped support plane
   * left out), or six point spacings of the sparser cloud where that is less
   * (a dense scene: a LiDAR frame, a drone survey, an object scan of millions of points), at
   * least three times its noise and a quarter of the 2.5% (Rust: `arps::grain`); the result's
   * `maxCorrespondenceDistance` says which. ICP runs coarse to fine at 4x, 2x and 1x this
   * distance; `fitness` and `inlierRmse` are measured at 1x (the confidence's evidence at the
   * 2.5%, or at a smaller distance you give). Must be > 0, and at most the clouds' shared
   * half-extent (beyond it every point pairs with one, whatever the pose).
   */
  maxCorrespondenceDistance?: number | null,
  /**
   * Iteration cap of each of the three ICP stages. Default 30; at least 1, at most 10000
   * (`icp: "off"` leaves ICP out). The answer's
   * final stage, when it has not converged within the cap, runs on for up to three more
   * rounds of as many while it still moves (a slow fit is not judged where the cap cut it;
   * `icpConverged` says whether it converged).
   */
  icpMaxIterations?: number,
  /**
   * How ICP weighs its pairs: `"robust"` (the default: each pair weighed by Tukey's biweight
   * of its residual, so that a surface that changed between the scans, such as eroded cliffs,
   * a new building, a dug pit, moved furniture or a bent part, no longer pulls the answer; in
   * every stage of the refinement of `initialTransform`, which the wide stages would
   * otherwise pull off a right guess, and in one more refinement of the search's answer, at
   * the scale of the pairs' spread and by a graduated descent of fixed scales from half the
   * distance down, from the answer and from `initialTransform`, so that a change within the
   * distance, which pulled least squares far enough to spread every residual, is left out
   * too; that pose replaces the least-squares answer only where clearly more of the source
   * lies on the target's surfaces, so where nothing changed the answer is least squares' but
   * for a few pairs in a hundred) or
   * `"squared"` (every pair within the distance alike, throughout). A change over half the
   * overlap is the scene to any robust weighting, and without a guess near the truth one that
   * tilted the fit by about its own height is not told from the rest.
   */
  icpLoss?: IcpLoss,
  /**
   * Voxel size of the clouds ICP works on, in the clouds' units. Default: half the final max
   * correspondence distance, or of the default distance when `maxCorrespondenceDistance` is
   * wider (the voxels the answer's evidence is measured on). `0` uses the full clouds, as does
   * a size below a millionth of the clouds' shared half-extent. Must be >= 0, and at most the
   * clouds' shared half-extent.
   */
  voxelSize?: number | null,
  /**
   * An initial guess of `T_target_source` (rigid, the clouds' units); the network then
   * estimates the remaining motion from there, the adaptive search refines the guess itself
   * (the `"initial"` start, when `starts` has it) with the first start, and of two answers that
   * fit about as well, the one nearer the guess's rotation wins (see `starts`). An answer that
   * turns more than 60 degrees away from the guess (`GUESS_TURN_DEG`) contradicts it: its
   * confidence is at most 0.25, with a warning (the guess was off, or the answer is a
   * look-alike: 30-100 probe points on a vertebra, turned over, fit 0.89-0.97 of them). An
   * answer that puts the
   * source farther than half its size from where the guess puts it comes with a warning (a
   * look-alike elsewhere, when the guess placed it). Along a motion the fit leaves free
   * (`evidence.constraint`: a jar's turn about its axis between two turntable views) the answer
   * follows the guess, with a warning, since the clouds cannot place it there; so it does along
   * a motion the fit barely holds (`evidence.slide`: a nearly round teapot) when the answer
   * turned more than 10 degrees from the guess (a guess off along such a motion is then off as
   * much, at a confidence of 0.25 or less). Default:
   * the identity. Either 16
   * numbers in **column-major** order (a previous result's `T_target_source`, a three.js
   * `Matrix4.elements`; in JS also a `Float32Array` or `Float64Array`), or four **row-major**
   * rows `[[r00, r01, r02, tx], [r10, r11, r12, ty], [r20, r21, r22, tz], [0, 0, 0, 1]]`. A
   * non-rigid or non-finite matrix is an error; with `sourceScale`, its 3x3 part is a rotation
   * times that factor, as the result's is. (In Rust: four row-major rows.)
   */
  initialTransform?: ArrayLike<number> | number[][] | null,
  /**
   * What to do with points that have a NaN or infinite coordinate, or one beyond 1e18 from the
   * cloud's origin (where the engine's `f32` distances overflow: a sensor's `f32::MAX` for "no
   * return"): `"error"` (an error naming the first bad point; the default) or `"drop"` (ignore
   * them, e.g. PCD "no return" points).
   */
  nonFinite?: NonFinite,
  /**
   * What to do with points that lie far out from the rest of their cloud (stray returns,
   * reflections: outside the box of the points whose few nearest neighbours are close, and
   * with no others around them): `"drop"` (leave them out, with a warning that counts them;
   * the default) or `"keep"`. A few such points would otherwise inflate the bounding box that
   * the clouds are normalised by. A cloud without them is used exactly as given either way.
   */
  outliers?: Outliers,
  /**
   * What to do with a support plane, the table or floor under a scanned object: `"drop"` (leave
   * it out of each cloud that stands on one, with a warning that counts its points; the default)
   * or `"keep"`. A support plane holds a tenth or more of its cloud, has nearly all the rest of
   * the cloud on one side, reaches out beyond what stands on it on at least three sides (with at
   * least 30% of its points outside the footprint of the rest), and is one layer (a sheet's two
   * faces are not a table; nor is a plane with the object's own bottom face sampled just above
   * it, which no capture of an object on a table sees). At least a tenth of the cloud stands off
   * it, or a hundredth when the other cloud stands on a support plane: a view that is nearly all
   * table around a small object loses its table when the other view does, and both are left out.
   * Left in a scan registered onto a model of the object, it sets the clouds' scale and the
   * object's flat faces are drawn onto it; between two scans it pulls the answer towards the
   * table's motion, which differs from the object's when the object was tipped or turned over
   * between them. Keep it for two scans of an object that stood still on its table, where the
   * shared table helps.
   */
  supportPlane?: SupportPlane,
  /**
   * The direction that is up in both clouds' frames, when both were captured level: scans
   * from a phone or a terrestrial scanner (gravity-aligned), survey data, a CAD model in its
   * upright pose (`[0, 0, 1]` for z-up data, `[0, 1, 0]` for three.js's y-up). The answer then
   * only turns the source about this axis, within `UP_TOLERANCE_DEG` of tilt for scans
   * levelled a little differently: every start is levelled first (its tilt off `up` taken
   * out, ICP then finds the small tilt between the scans; with `icp: "off"` the answer is
   * the levelled start, so leave `up` out to judge a pose as given), answers tilted further are
   * rejected, and look-alikes tilted further do not count as alternatives; the answer turned
   * a quarter and a half turn about up, each placed where the global descriptors' matches
   * agree, is refined too (a box-like room captured from another spot fits its turns about as
   * well), and counts as an alternative or replaces the answer when it fits about as well or
   * clearly better. When a rejected,
   * tilted answer fits clearly better than the upright one, `up` probably does not hold: a
   * warning says so and the confidence is at most 0.25. It is the same direction in both
   * clouds' frames, whatever `initialTransform` says. Default: none (any rotation). Three
   * finite numbers, not all zero (any length).
   */
  up?: [number, number, number] | null,
  /**
   * The share of the source that lies on the target once aligned, when the caller knows it:
   * `1` for a scan of an object onto a complete model of it (a CAD part read as its surface),
   * or a frame onto a map that covers everything the frame sees; less where the source also
   * holds what the target lacks (clutter around the part, people in the frame, what lies beyond
   * the map's edge). Default: none (unknown, as between two partial views, which may overlap by
   * any share). With it, an answer under which clearly less of the source lies near the target
   * (its share within twice the distance the answer is judged at, `evidence.fitnessLoose`,
   * below `sourceOverlap - 0.15`) is not taken as sure: the adaptive search goes on as for an
   * unsure answer, and when the answer still falls short its confidence is at most 0.25, with a
   * warning that gives the share (the wrong model, a mirror-image export, a scale or unit
   * error, points the target lacks left in the source, or a pose the search did not find).
   * With it, the source's mirror images are also refined from the answer: when one fits
   * clearly better, the confidence is at most 0.25, with a warning (a mirrored part, an export
   * with one axis flipped). A number in (0, 1].
   */
  sourceOverlap?: number | null,
  /**
   * The factor that takes the source's coordinates into the target's unit, when they differ:
   * `1000` for a scan in metres onto a model in millimetres, `0.001` the other way, `0.0254`
   * for inches onto metres. The source's points are multiplied by it before anything else;
   * every distance (`maxCorrespondenceDistance`, `voxelSize`, the result's `inlierRmse`) is then
   * in the target's unit. `T_target_source` (the result's, its alternatives' and
   * `initialTransform`) still maps the source's points **as given** into the target frame: its
   * 3x3 part is the rotation times this factor, so three.js's `matrix.fromArray` places the
   * source object and `transformFile` moves the source's file as they are. Default: none (the
   * same unit, a factor of 1). A finite number > 0.
   */
  sourceScale?: number | null,
  /**
   * The transforms ICP starts from, in order of preference. Each is refined coarse to fine
   * against the same prepared target and the best is returned (the result's `start` says
   * which): the highest `fitness`, ties going to the lower `inlierRmse`, then to the earlier
   * start; but of two answers whose fitness is within 10% and whose turns away from
   * `initialTransform` (the identity if unset) differ by more than 60 degrees, the one that
   * turns less (a near-symmetric shape's half turn fits about as well as the truth; the
   * smaller motion is the likelier). Starts that meet during refinement are refined once, as
   * the earlier; on large clouds the starts are compared on 2048 of the source points and only
   * the winner is refined on 8192 of them. Which starts are refined at all depends on
   * `search`. Default `["network", "global", "centroids", "initial", "turned",
   * "turnedInitial", "rotationsNetwork"]`; each extra start costs one ICP run on at most 2048
   * points (`"turned"` and `"turnedInitial"` are six each, `"global"` and `"globalNetwork"` up
   * to five each, plus the descriptor matching, `"rotations"` 24, `"rotationsNetwork"` 24 and
   * as many network passes), so `["network"]` is the fastest, and the least sure: when the
   * network turns the source wrong (a half turn), no other start corrects it, and the
   * confidence may not tell (two vehicle LiDAR sweeps at a 20-degree turn came back turned over
   * at 0.98). Must be non-empty, without repeats.
   * - `"network"`: the network + GMR estimate (with `network: false`, the initial transform,
   *   reported as `"initial"`);
   * - `"centroids"`: `initialTransform`'s rotation (none if unset) with the translation that
   *   moves the source's centroid onto the target's;
   * - `"initial"`: `initialTransform` itself (the identity if unset);
   * - `"turned"`: six starts, the network estimate (the initial transform with
   *   `network: false`) turned 45 degrees both ways about each axis through the source's
   *   centroid, for estimates that landed outside ICP's basin;
   * - `"turnedInitial"`: six starts, `initialTransform` (the identity if unset) turned the same
   *   way, for pairs where the network's estimate is far off (with `network: false`, the same
   *   starts as `"turned"`, reported as `"turned"`);
   * - `"global"`: up to five hypotheses from global registration (FPFH descriptors, mutual
   *   matches, a seeded RANSAC), for motions of any size, e.g. scans in unrelated frames; none
   *   when the descriptors match too little;
   * - `"globalNetwork"`: the `"global"` hypotheses, each refined by the network first (with
   *   `network: false`, the same starts as `"global"`, reported as `"global"`);
   * - `"rotations"`: 24 starts, the source's centroid moved onto the target's and turned by
   *   each rotation of a cube onto itself (after `initialTransform`'s rotation): a blind
   *   search over every orientation, for shapes whose descriptors match poorly (repetitive,
   *   smooth or symmetric ones). Not in the default list; the adaptive search adds them to its
   *   last stage (see `search`);
   * - `"rotationsNetwork"`: the `"rotations"` turns, each refined by the network first (it
   *   estimates the motion left after the turn; every orientation is within about 63 degrees
   *   of one of them): a search over every orientation that, unlike the blind one, lands near
   *   the truth where ICP alone would not. The adaptive search refines them only for an answer
   *   still unsure (confidence below 0.5) after every other stage (see `search`). It needs the
   *   network: with `network: false` it is left out, and naming it alone is an error.
   *
   * The refined answer is then probed for poses that fit about as well (the `confidence`'s
   * turns, `evidence.ambiguity`); when one fits better (typically the answer flipped about an
   * axis of an elongated shape), it is refined like one more start, reported under the start
   * it came from, and kept if it fits best. While the answer's confidence is below 0.95, a
   * stage's best that does not replace it is probed too, since its flip may. When either cloud
   * has many points (see `search`), the stages before the global one are probed only once it
   * has run: the better of their answer and its answer first.
   *
   * With `icp: "off"` nothing is refined or compared: the first start is the answer.
   */
  starts?: Array<RegistrationStart>,
  /**
   * How `starts` are searched. Default `"adaptive"`: in stages, stopping as soon as the best
   * answer's `confidence` reaches 0.95 (`STOP_CONFIDENCE`): the first start alone (with
   * `initialTransform` given, and `"initial"` in `starts`, with that start); then the
   * others in order, each run of local starts or of global ones (`"global"`,
   * `"globalNetwork"`) one stage (with the default starts: the global ones, then the other
   * local ones). When every stage has run without reaching 0.95 and `starts` has a global
   * kind, a last stage refines up to ten more global hypotheses (the next best of a second,
   * larger RANSAC draw on the same descriptor matches) and the 24 `"rotations"` starts
   * (unless `starts` names them), of which the 12 that fit best after a short ICP run each
   * are refined; so only the pairs no stage settled pay for them. Its starts are blind, so its
   * best replaces the answer only when it fits more than 10% better. An answer whose
   * confidence reaches 0.85 once the global stage has run (`NEARLY_SURE_CONFIDENCE`), or 0.5
   * when the global stage's best hypothesis, refined, is that same pose (`AGREED_CONFIDENCE`),
   * skips the stages left, and its last stage refines only the 3 best of those further
   * hypotheses. Then, when `starts` has `"rotationsNetwork"` and the answer's confidence is
   * still below 0.5 (`UNSURE_CONFIDENCE`), those starts are refined, as one more stage whose
   * best replaces the answer only when it fits more than 15% better (it searches every
   * orientation, where a look-alike can fit a few percent better than the truth); so only the
   * answers the engine would otherwise flag as unsure pay for their network passes. Once a
   * global stage has run, the answer's rotation with the translation the descriptor matches
   * agree on for it is refined as one more start when that translation is another one, and
   * replaces the answer when it fits more than 10% better (an answer slid along a wall, its
   * rotation right); so is, at the final distance only, the answer's rotation at the next
   * translation they agree on, when it already fits half as well as the answer (the other of
   * two alike parts side by side, such as identical pipe spools: an alternative when it fits
   * about as well). Then, when most of the source lies on thin walls (another face parallel
   * to its own within ten final distances), the answer moved onto those other faces is
   * refined at the final distance, and replaces it when it fits better, its points no farther
   * (a one-view scan of sheet metal settled on the inner faces); one that fits alike comes
   * with a warning, as a flat sheet's two faces cannot be told apart. `"exhaustive"` refines every start, in the same stages (the starts for
   * unsure answers in their place in `starts`), each stage's best judged as above, without
   * the stops and without those last stages. The result's `startsRefined` says how many were
   * refined.
   */
  search?: RegistrationSearch,
};

/**
 * A transform ICP starts from (the options' `starts`, which describe each).
 */
export type RegistrationStart = "network" | "centroids" | "initial" | "turned" | "turnedInitial" | "global" | "globalNetwork" | "rotations" | "rotationsNetwork";

/**
 * How the options' `starts` are searched (see `search`).
 */
export type RegistrationSearch = "adaptive" | "exhaustive" | "local";

/**
 * Which ICP to run after the network.
 */
export type IcpKind = "off" | "point" | "plane";

/**
 * How ICP weighs the answer's pairs (`Options::icp_loss`).
 */
export type IcpLoss = "squared" | "robust";

/**
 * What to do with points that have a NaN or infinite coordinate, or one beyond
 * `MAX_COORDINATE` (1e18) from the cloud's origin.
 */
export type NonFinite = "error" | "drop";

/**
 * What registration does with the points that lie far out from the rest of their cloud
 * (`Options::outliers`).
 */
export type Outliers = "drop" | "keep";

/**
 * What registration does with a support plane, the table or floor under a scanned object
 * (`Options::support_plane`).
 */
export type SupportPlane = "drop" | "keep";

/**
 * A stage of a registration, reported as it starts (to `Registrar::register_with_progress`'s
 * callback in Rust, to `onProgress` in JS, as `"preparing"`, `"network"`, `"refining"`); stages
 * that do not run are skipped.
 */
export type RegistrationStage = "preparing" | "network" | "refining";

/**
 * The result of one registration. In JS (`Registrar.register`) and JSON (`arps register
 * --json`) it is a plain object with these fields in camelCase, the transforms as 16
 * column-major numbers (the conventions are in the `arps::contract` module docs and
 * `js/README.md`); safe to `postMessage`, `structuredClone` or `JSON.stringify`.
 */
export type RegistrationResult = {
  /**
   * The answer, `T_target_source`: the rigid transform that maps source points into the
   * target frame (`p_target = R p_source + t`), in the clouds' units, after ICP (with the
   * options' `sourceScale` `s`, `p_target = s R p_source + t`: the source as given). In JS and
   * JSON 16 numbers in **column-major** order (element (row r, col c) at index `c * 4 + r`),
   * ready for three.js: `sourceObject.matrix.fromArray(result.T_target_source)`.
   */
  T_target_source: number[],
  /**
   * The coarse estimate before ICP (network + GMR, or `initialTransform` with
   * `network: false`); same frames and layout as `T_target_source`.
   */
  T_target_source_network: number[],
  /**
   * The start (one of the options' `starts`) whose refinement is `T_target_source`.
   */
  start: RegistrationStart,
  /**
   * Fraction of (voxelised) source points that have a target point within
   * `maxCorrespondenceDistance` under `T_target_source`, in [0, 1]. Right answers on partial,
   * independently sampled scans often score only 0.15-0.3: judge the result by `confidence`.
   * Measured on at most 8192 source points, evenly spread.
   */
  fitness: number,
  /**
   * RMS distance of those inlier pairs, in the clouds' units (0 when there are none).
   */
  inlierRmse: number,
  /**
   * ICP iterations over all stages of the chosen start's refinement (0 with `icp: "off"`).
   */
  icpIterations: number,
  /**
   * True when the chosen start's last ICP stage met its convergence criteria (false with
   * `icp: "off"`).
   */
  icpConverged: boolean,
  /**
   * The final max correspondence distance used, in the clouds' units (the default resolved).
   */
  maxCorrespondenceDistance: number,
  /**
   * Time per stage, in milliseconds.
   */
  timings: RegistrationTimings,
  /**
   * Things to know about this result (input resampled, low confidence, ...), as sentences
   * for people. One starting with `"low confidence"` comes with every result whose
   * `confidence` is below 0.5. Test for a kind of warning with `warning_codes`, not by
   * matching these sentences: they name figures, and may be reworded.
   */
  warnings: Array<string>,
  /**
   * The kind of each warning, in the same order as `warnings` (`warning_codes[i]` is the
   * kind of `warnings[i]`): what code tests for (`warningCodes.includes("sizeMismatch")`).
   * Every result whose `confidence` is below 0.5 holds `WarningCode::LowConfidence`.
   */
  warningCodes: Array<WarningCode>,
  /**
   * An estimate of the probability that `T_target_source` is right (within the evaluation's
   * recall thresholds), in [0, 1]: a logistic model over `evidence`, calibrated on validation
   * pairs (`arps::confidence`). Read it as "likely right" near 1, "likely wrong" near 0; below
   * 0.5 `warnings` says the alignment may be wrong. It judges the fit and whether the fit is
   * unique: on a symmetric or featureless shape where other poses fit about as well
   * (`evidence.alternatives`, `evidence.ambiguity`, `evidence.slide`) it is low even when the
   * answer happens to be right, since nothing in the clouds tells the poses apart.
   */
  confidence: number,
  /**
   * The figures `confidence` is computed from, measured under `T_target_source`.
   */
  evidence: RegistrationEvidence,
  /**
   * How many distinct starts were refined (after merging those that met), counting the
   * probe poses refined as starts (see the options' `starts`); see the options' `search`.
   */
  startsRefined: number,
  /**
   * Other poses that fit about as well as `T_target_source` (at least 0.9 of its fitness when
   * found, by the confidence's probes or by the search, more than 15 degrees from it and from
   * each other, or as turned but placing the source more than 0.2 of the clouds' half-extent
   * away: a facade's next window bay), each refined like the answer, the best fitting first;
   * empty when the fit is unique. One may fit a little better than the answer, which the search
   * chose among near ties by its turn; one that leaves less than half as much of the source off
   * the target becomes the answer. On a symmetric shape the right pose is often one of these
   * rather than the answer, and nothing in the clouds tells them apart: an application can offer
   * them to its user. `evidence.alternatives` counts those of the probes or of the search,
   * whichever found more (the confidence's input), so this list can be longer; a refinement that
   * brings a pose back onto the answer or onto another drops it, so it can also be shorter.
   */
  alternatives: Array<RegistrationAlternative>,
  /**
   * The motions the fit leaves free, weakest held first; empty when the fit pins every motion.
   * Along each, the surfaces keep the source on the target (a surface of revolution turned about
   * its axis, a straight pipe, tunnel or extrusion slid along itself, a plane slid or turned in
   * itself), or nearly (small features repeated along it: holes on a bolt circle, a gear's
   * teeth), so only where the clouds' edges fall, or those features, holds the answer there, and
   * it may be off along it: what the warning `"freeMotion"` names in words, as numbers an
   * application can draw or constrain (with a guess, `initialTransform`, the answer follows the
   * guess along them: `"heldByGuess"`).
   */
  freeMotions: Array<RegistrationFreeMotion>,
};

/**
 * The kind of a registration's warning: `warningCodes[i]` is the kind of `warnings[i]`. One
 * code may come with several sentences (the source's and the target's, or two causes of one
 * doubt). New codes may be added (in Rust the enum is `#[non_exhaustive]`: a `match` needs a
 * wildcard arm); a caller that meets one it does not know should show the sentence.
 *
 * * `"lowConfidence"`: the confidence is below 0.5, or another pose fits about as well
 *   (`alternatives`): the alignment may be wrong. Comes with every result whose `confidence` is
 *   below 0.5.
 * * `"sizeMismatch"`: the clouds differ in size by a large factor: probably different units
 *   (metres and millimetres); the option `sourceScale` scales the source.
 * * `"coarseCoordinates"`: a cloud's coordinates were rounded to 32-bit floats far from zero (a
 *   map grid given as `Float32Array`, a file that stores floats), to steps that can make the
 *   answer as coarse.
 * * `"distanceTooFine"`: the distance the answer is judged at is finer than `f32` coordinates
 *   resolve there.
 * * `"distanceTooWide"`: the source is small against the distance the answer is judged at: it fits
 *   about as well turned or moved, so the fit cannot confirm its pose (different units, or too
 *   wide a `maxCorrespondenceDistance`).
 * * `"nearlyLine"`: a cloud is nearly a line: the rotation about it is weakly held.
 * * `"bothFlat"`: both clouds are flat: sliding within the plane and turning about its normal are
 *   held only by their outlines.
 * * `"freeMotion"`: the fit leaves a motion free (a surface of revolution, a straight pipe or
 *   tunnel, a plane): only the clouds' edges hold the answer along it (`evidence.constraint`).
 * * `"thinWall"`: the source fits about as well moved onto a parallel face within ten final
 *   distances: the other face of a thin wall or sheet, or the next of a repeated structure (a
 *   building's floors one storey apart at a default distance of half a metre).
 * * `"mirrorImage"`: a mirror image of the source fits clearly better: one cloud is probably
 *   mirrored (a left part for a right one, an axis flipped on export).
 * * `"lowOverlap"`: less of the source lies on the target than `sourceOverlap` says it should.
 * * `"notUpright"`: with `up`: a tilted pose fits clearly better than the upright answer (the
 *   clouds were not both captured level).
 * * `"unrefined"`: no start could be refined (or none ended upright with `up`): the answer is the
 *   network's estimate or the initial transform, unrefined.
 * * `"turnedFromGuess"`: the answer turned far from `initialTransform` (more than 60 degrees; its
 *   confidence is then at most 0.25): the guess was off, or the answer is a look-alike. With
 *   `starts: ["initial"]`, the guess as the one start, it also says how far the answer moved from
 *   the guess whenever it ended at another pose (no cap below 60 degrees).
 * * `"farFromGuess"`: the answer places the source far from where `initialTransform` does: a
 *   look-alike elsewhere (a repeated room, the next bay) if the guess placed it.
 * * `"heldByGuess"`: along a motion the fit leaves free (or barely holds, when the answer turned
 *   more than 10 degrees from the guess), the answer follows `initialTransform`: the guess, not
 *   the clouds, placed it there (the result names the motion in `freeMotions`).
 * * `"betterPoseNotTaken"`: with `search: "local"`: a pose the probes found fits better than the
 *   answer; it is offered among the alternatives, not taken.
 * * `"fewPoints"`: the source has too few points to be sure of any answer, or the clouds are too
 *   sparse for the distance the answer is judged at (points many times that distance apart).
 * * `"networkResampled"`: a cloud has fewer points than the network takes: it saw some twice (the
 *   answer is still refined on every point).
 * * `"nonFiniteDropped"`: points with a non-finite coordinate (or one beyond 1e18) were left out
 *   (`nonFinite: "drop"`).
 * * `"outliersDropped"`: outliers were left out (`outliers: "drop"`).
 * * `"supportPlaneDropped"`: a support plane (a table, a turntable, the floor) was left out
 *   (`supportPlane: "drop"`).
 * * `"pointsAtZero"`: several points lie exactly at (0, 0, 0), as a depth camera writes its
 *   pixels without a return: they are registered as points; remove them.
 * * `"meshVertices"`: the CLI read a mesh file's vertices as the cloud (`--surface-points` samples
 *   its surface).
 */
export type WarningCode = "lowConfidence" | "sizeMismatch" | "coarseCoordinates" | "distanceTooFine" | "distanceTooWide" | "nearlyLine" | "bothFlat" | "freeMotion" | "thinWall" | "mirrorImage" | "lowOverlap" | "notUpright" | "unrefined" | "turnedFromGuess" | "farFromGuess" | "heldByGuess" | "betterPoseNotTaken" | "fewPoints" | "networkResampled" | "nonFiniteDropped" | "outliersDropped" | "supportPlaneDropped" | "pointsAtZero" | "meshVertices";

/**
 * Milliseconds spent in each stage of one registration (0 where no clock is available; in JS
 * measured with `performance.now()`).
 */
export type RegistrationTimings = {
  /**
   * Validation, normalisation, network sampling and ICP voxel downsampling.
   */
  preprocessMs: number,
  /**
   * The network's forward passes: its estimate's, and those (with their GMR solves) of the
   * starts it refines first, `"globalNetwork"` and `"rotationsNetwork"` (0 with
   * `network: false`).
   */
  networkMs: number,
  /**
   * GMM parameters and the weighted Procrustes solve.
   */
  gmrMs: number,
  /**
   * ICP from every start (normals, kd-tree, iterations) and the quality figures.
   */
  icpMs: number,
  /**
   * Global hypotheses (descriptors, matching, RANSAC); 0 when no global start ran.
   */
  globalMs: number,
  /**
   * The whole registration inside the engine.
   */
  totalMs: number,
};

/**
 * The evidence behind `confidence`, measured on the (voxelised) clouds under the answer, in
 * multiples of a distance `d`: the final max correspondence distance, or the default one (0.025
 * of the clouds' largest half-extent, where the confidence is calibrated) when that is smaller,
 * so that a wider distance the caller chose does not make every pose look right.
 */
export type RegistrationEvidence = {
  /**
   * Fraction of source points with a target point within `d` (the result's `fitness` when `d`
   * is the final distance).
   */
  fitness: number,
  /**
   * The same within `d / 2`.
   */
  fitnessTight: number,
  /**
   * The same within `2 d`.
   */
  fitnessLoose: number,
  /**
   * The same within `4 d`.
   */
  fitnessCoarse: number,
  /**
   * Fraction of target points with a source point within `d` (overlap the other way).
   */
  overlapReverse: number,
  /**
   * Inlier RMSE at `d`, divided by `d` (0 without inliers).
   */
  rmseRatio: number,
  /**
   * How well the best *different* pose fits, as a fraction of the answer's fitness (at most
   * 2): the answer turned 90 degrees both ways and 180 degrees about each principal axis of
   * the moved source, 180 degrees about the four diagonals between those axes and about each
   * principal axis of the target points it overlaps (all through the moved source's
   * centroid), 180 degrees about each principal axis of the whole target through its centroid
   * when the source covers a much smaller share of the target than the target of the source (a
   * scan onto a model, which may fit as well on the model's other end), and 60 degrees both
   * ways along the least constrained motion of `Evidence::slide` (when that slide is at least
   * 0.3), each refined by a short ICP; 0 when every one fell back onto the answer (within 15
   * degrees and 0.2 of the clouds' half-extent). Near 1 or above: the answer may fit and still
   * not be unique.
   */
  ambiguity: number,
  /**
   * How many distinct poses (more than 15 degrees apart, or putting the source's centre more
   * than 0.2 of the clouds' half-extent apart: a repeating structure's next element) fit at
   * least 0.9 as well as the answer, among those probes (and the answer turned a quarter, a
   * third and a fifth about an axis the source, or for a part the whole target, is round
   * about) or, when more, among the other answers the
   * search refined (its stages' best answers and the probes' better poses): with `k`
   * alternatives the answer is one of `k + 1` about equally good poses.
   */
  alternatives: number,
  /**
   * Fitness after sliding the answer along the motion its point-to-plane fit constrains
   * least (the weakest eigenvector of the fit's 6x6 information matrix, scaled to move the
   * points 0.25 of the normalised half-extent on average), the better of both ways, as a
   * fraction of the answer's fitness (at most 2). Near 1: the fit does not pin the pose down
   * along that motion (a surface of revolution, a plane, a cylinder, a tunnel). At
   * `SLID_FREE` or above the motion counts as free, as for `Evidence::constraint`: the
   * confidence is at most 0.25, with a warning naming the motion.
   */
  slide: number,
  /**
   * How firmly the fit pins down that least constrained motion: the weakest eigenvalue of the
   * point-to-plane fit's 6x6 information matrix (normalised units, about the inliers' centroid)
   * over the strongest, in [0, 1]; 1 when too few points pair up to measure it. Below
   * `UNPINNED_CONSTRAINT` the shapes' surfaces leave that motion free (a surface of revolution
   * turned about its axis, a straight pipe or extrusion slid along itself, a plane in itself):
   * only where the clouds' edges fall holds the pose there, and the answer's confidence is at
   * most 0.25, with a warning naming the motion. Not an input of the logistic model.
   */
  constraint: number,
};

/**
 * Another pose that fits about as well as the answer (one of the result's `alternatives`):
 * frames, units and layout as the answer's.
 */
export type RegistrationAlternative = {
  /**
   * The pose, `T_target_source`, in the clouds' units; in JS and JSON 16 numbers in
   * column-major order, like the answer's.
   */
  T_target_source: number[],
  /**
   * Its fitness, measured like the answer's `fitness`.
   */
  fitness: number,
  /**
   * Its inlier RMSE, measured like the answer's `inlierRmse`, in the clouds' units.
   */
  inlierRmse: number,
};

/**
 * A motion the fit leaves free (one of the result's `freeMotions`): a turn about an axis or a
 * slide along a direction, in the target's frame and units.
 */
export type RegistrationFreeMotion = {
  /**
   * A turn about an axis, or a slide.
   */
  kind: FreeMotionKind,
  /**
   * The turn's axis or the slide's direction: a unit vector in the target's frame (either
   * sign: the motion is free both ways).
   */
  direction: [number, number, number],
  /**
   * For a turn, the point of its axis nearest the fitted points' centroid; for a slide, that
   * centroid (where to draw it); in the target's frame (with its origin: map-grid coordinates
   * as given).
   */
  through: [number, number, number],
};

/**
 * What a `FreeMotion` is.
 */
export type FreeMotionKind = "turn" | "slide";

/**
 * How `read_point_cloud_with` turns a file into points. In JS (`parsePointCloud`,
 * `readPointCloud`) a plain object with these fields in camelCase, each optional.
 */
export type ReadOptions = {
  /**
   * For a file with faces (OBJ, OFF, STL, glTF/GLB, PLY with a `face` element): this many points drawn
   * uniformly over its surface instead of its vertices. A CAD model's vertices sit on its
   * edges and corners, and its flat faces have none, so a scan registers against its surface,
   * not its vertices. From 16 to 16,000,000; files without faces are read as they are. Unset
   * (the default): the vertices.
   */
  surfacePoints?: number | null,
  /**
   * Seed of the surface sampling: the same file, count and seed give the same points on every
   * platform. Default 0. A non-negative integer (in JS a `bigint` from 2^53 on: a number that large may have been rounded).
   */
  seed?: number | bigint,
  /**
   * For an E57 file, which holds one point cloud per scan: only this one (0-based, in the
   * file's order), placed by its pose. An index beyond the file's scans is an error, and so is
   * setting it for a file of another format (one cloud, nothing to choose: `list_scans` gives
   * an empty list). Unset (the default): every scan, as one cloud.
   */
  scan?: number | null,
  /**
   * For a LAS or LAZ file: only the points of these classification codes (ASPRS: 2 ground,
   * 3-5 vegetation, 6 building, 7 low noise, 9 water, 18 high noise, ...), e.g. `[2]` to
   * register two epochs by their ground where vegetation or buildings changed, or every code
   * but the noise ones. An error when no point of the file is of them (the message names the
   * classes it holds), when the list is empty, and for a file of another format (it has no
   * classes). `transform_file` moves every point of the file whatever this says. Unset (the
   * default): every point.
   */
  classes?: number[],
  /**
   * For a Gaussian splat PLY (a vertex `opacity` property, the logit the splat file stores):
   * only the splats at least this opaque (the logit's sigmoid, in [0, 1]; 0.5 keeps those
   * with a logit of 0 or more). Splat scenes hold transparent floaters strewn about and huge
   * background splats that can mislead the search; their surfaces are the opaque splats. An
   * error when no splat is that opaque, for a PLY without `opacity`, with `surfacePoints`, and
   * for a file of another format. `transform_file` moves every splat of the file whatever
   * this says. Unset (the default): every splat.
   */
  minOpacity?: number | null,
};

/**
 * One scan of a file that holds several (E57), as `list_scans` describes it. In JS a plain
 * object with these fields.
 */
export type ScanInfo = {
  /**
   * The scan's name in the file, if it has one (often the scanner's station name).
   */
  name: string | null,
  /**
   * The scan's point records, invalid ones (no return) included: an upper bound of the points
   * read. A non-negative integer (in JS a `number`).
   */
  records: number,
};

/**
 * Every size of the network. Stored as JSON in the weights file's metadata, with snake_case
 * keys; in JS (`Registrar.modelConfig`) the keys are camelCase (`arps::contract`).
 */
export type ModelConfig = {
  /**
   * Preset name this config started from (`web`, `paper`, or a custom label).
   */
  preset: string,
  /**
   * Network points per cloud, N.
   */
  nPoints: number,
  /**
   * Per-point feature width C; attention tokens are `2C` wide (`[f ; phi]`).
   */
  featureDim: number,
  /**
   * Attention heads; `2C` must be divisible by it.
   */
  heads: number,
  /**
   * Hidden width of each attention block's feed-forward network.
   */
  ffnDim: number,
  /**
   * Number of ARPS layers, L.
   */
  layers: number,
  /**
   * Top-H size of the `"top_h"` reference rule.
   */
  topH: number,
  /**
   * Number of Gaussians, J.
   */
  gaussians: number,
  /**
   * Hidden widths of the position MLP `3 -> ... -> C`.
   */
  posHidden: Array<number>,
  /**
   * Hidden width of the step-size MLP `(3 + C) -> hidden -> 1`.
   */
  stepHidden: number,
  /**
   * Hidden widths of the membership head `2C -> ... -> J`.
   */
  headHidden: Array<number>,
  /**
   * Reference-point rule.
   */
  reference: ModelReference,
  /**
   * Softmax temperature of the `"soft"` reference rule.
   */
  softTemperature: number,
  /**
   * LayerNorm epsilon.
   */
  layerNormEps: number,
};

/**
 * How each ARPS layer picks its reference point.
 */
export type ModelReference = "top_h" | "soft";
