/**
 * A point cloud, packed xyz `[x0, y0, z0, x1, ...]` (at least 16 finite points):
 * - a `Float32Array`, used as is;
 * - a `Float64Array`: for large coordinates (e.g. georeferenced scans). The engine works on
 *   float32 offsets from the cloud's bounding-box centre, and the result (`matrix64`) is mapped
 *   back in float64, exact in your frame;
 * - `{ points, origin }`: float32 `points` relative to `origin` (`[x, y, z]`, float64), e.g. what
 *   `readPointCloud` returns; the result is in the frame of `points + origin`;
 * - an `Array` of numbers (copied into a `Float32Array`).
 */
export type CloudInput = Float32Array | Float64Array | number[] | CloudWithOrigin;

/**
 * A cloud as float32 offsets from a float64 origin: point `i` is `origin + points[i]` (what
 * `readPointCloud` returns, and a `CloudInput`).
 */
export interface CloudWithOrigin {
  /** Packed xyz offsets from `origin`, `[x0, y0, z0, x1, ...]`. */
  points: Float32Array;
  /** `[x, y, z]`, in your units (float64). */
  origin: ArrayLike<number>;
}

/**
 * Options of `Registrar.register`. Every field is optional; a missing, `undefined` or `null`
 * field takes its default (the core `arps::Options`, field by field). Unknown or misspelled
 * fields, wrong types and out-of-range values throw an `Error` naming the field.
 */
export interface RegisterOptions {
  /**
   * Points per cloud fed to the network (each cloud is resampled to exactly this many; a cloud
   * with fewer points has some used twice, with a warning). Default: the model's N (128 for the
   * embedded model, `modelConfig.nPoints`). Range: the model's minimum up to 4096 (attention cost grows with its square).
   */
  networkPoints?: number | null;
  /**
   * Seed of every random choice (the network's point sampling). Default 0. The same inputs and
   * seed give the same output, bit for bit, on a given build. A non-negative integer
   * (a `bigint` for values above 2^53).
   */
  seed?: number | bigint;
  /**
   * Refinement after the network: `"plane"` (point-to-plane ICP, target normals; the default),
   * `"point"` (point-to-point ICP) or `"off"` (the network + GMR estimate is the answer).
   */
  icp?: "plane" | "point" | "off";
  /**
   * Run the network. Default `true`. With `false` the coarse estimate is `initialTransform`
   * (identity if unset) and only ICP runs: the classical baseline, or a refinement when a good
   * initial guess is known.
   */
  network?: boolean;
  /**
   * ICP's final maximum correspondence distance, in **your units** (those of the clouds).
   * Default: 2.5% of the clouds' shared half-extent. ICP runs coarse to fine at 4x, 2x and 1x
   * this distance; `fitness` and `inlierRmse` are measured at 1x. Must be > 0.
   */
  maxCorrespondenceDistance?: number | null;
  /** Iteration cap of each of the three ICP stages. Default 30; at most 10000. */
  icpMaxIterations?: number;
  /**
   * Voxel size of the clouds ICP works on, in your units. Default: half the final max
   * correspondence distance. `0` uses the full clouds. Must be >= 0.
   */
  voxelSize?: number | null;
  /**
   * An initial guess of `T_target_source` (rigid, your units); the network then estimates the
   * remaining motion from there. Default: identity. Either 16 numbers in **column-major** order
   * (a three.js `Matrix4.elements`, or a previous result's `matrix`), or four **row-major** rows
   * `[[r00, r01, r02, tx], [r10, r11, r12, ty], [r20, r21, r22, tz], [0, 0, 0, 1]]`
   * (the CLI's JSON layout). A non-rigid matrix throws.
   */
  initialTransform?: Float32Array | Float64Array | ArrayLike<number> | number[][] | null;
  /**
   * What to do with points that have a NaN or infinite coordinate: `"error"` (throw, naming
   * the first bad point; the default) or `"drop"` (ignore them, e.g. PCD "no return" points).
   */
  nonFinite?: "error" | "drop";
  /**
   * The transforms ICP starts from, in order of preference; each is refined (coarse to fine,
   * against the same prepared target) and the best is returned, with `start` saying which: the
   * highest `fitness`, ties going to the lower `inlierRmse`, then to the earlier start. Starts
   * that meet during refinement are refined once, as the earlier; on large clouds the starts are
   * compared on 2048 of the source points and only the winner is refined on 8192. Which
   * starts are refined at all depends on `search`. Default
   * `["network", "global", "centroids", "initial", "turned", "turnedInitial"]`; each extra start
   * costs one ICP run (on at most 2048 points; `"turned"` and `"turnedInitial"` are six each,
   * `"global"` and `"globalNetwork"` up to five each, plus the descriptor matching), so
   * `["network"]` is the fastest. Must be non-empty, without repeats.
   * - `"network"`: the network + GMR estimate (with `network: false`, the initial transform,
   *   reported as `"initial"`);
   * - `"centroids"`: `initialTransform`'s rotation (none if unset) with the translation that moves
   *   the source's centroid onto the target's;
   * - `"initial"`: `initialTransform` itself (the identity if unset);
   * - `"turned"`: six starts, the network estimate (the initial transform with `network: false`)
   *   turned 45 degrees both ways about each axis through the source's centroid, for estimates
   *   that landed outside ICP's basin;
   * - `"turnedInitial"`: six starts, `initialTransform` (the identity if unset) turned the same
   *   way, for pairs where the network's estimate is far off (with `network: false`, the same
   *   starts as `"turned"`, reported as `"turned"`);
   * - `"global"`: up to five hypotheses from global registration (FPFH descriptors, mutual
   *   matches, a seeded RANSAC), for motions of any size, e.g. scans in unrelated frames; none
   *   when the descriptors match too little;
   * - `"globalNetwork"`: the `"global"` hypotheses, each refined by the network first (with
   *   `network: false`, the same starts as `"global"`, reported as `"global"`).
   *
   * With `icp: "off"` nothing is refined or compared: the first start is the answer.
   */
  starts?: RegistrationStart[];
  /**
   * How `starts` are searched:
   * - `"adaptive"` (the default): in stages, stopping as soon as the best answer's `confidence`
   *   reaches 0.9: the first start alone; then the others in order, each run of local starts or
   *   of global ones (`"global"`, `"globalNetwork"`) one stage (by default: the global ones, then
   *   the other local ones). The best of everything refined is returned.
   *   Easy pairs cost one start; hard ones still get every start.
   * - `"exhaustive"`: every start is refined and the best returned (slower, never stops early).
   *
   * `startsRefined` in the result says how many were refined.
   */
  search?: RegistrationSearch;
}

/** How `RegisterOptions.starts` are searched (see `RegisterOptions.search`). */
export type RegistrationSearch = "adaptive" | "exhaustive";

/** A transform ICP starts from (see `RegisterOptions.starts`). */
export type RegistrationStart =
  | "network"
  | "centroids"
  | "initial"
  | "turned"
  | "turnedInitial"
  | "global"
  | "globalNetwork";

/** Milliseconds spent in each stage of one registration (measured with `performance.now()`). */
export interface RegistrationTimings {
  /** Validation, normalisation, network sampling and ICP voxel downsampling. */
  preprocessMs: number;
  /** The network forward pass (0 with `network: false`). */
  networkMs: number;
  /** GMM parameters and the weighted Procrustes solve. */
  gmrMs: number;
  /** ICP from every start (normals, kd-tree, iterations) and the quality figures. */
  icpMs: number;
  /** Global hypotheses (descriptors, matching, RANSAC); 0 when no global start ran. */
  globalMs: number;
  /** The whole `register` call inside the engine. */
  totalMs: number;
}

/** The result of `Registrar.register`: a plain object, safe to `postMessage` or `structuredClone`. */
export interface RegistrationResult {
  /**
   * The answer, `T_target_source`: the rigid 4x4 transform that maps source points into the
   * target frame (`p_target = R p_source + t`), in your units, after ICP. A `Float32Array(16)` in
   * **column-major** order (element (row r, col c) at index `c * 4 + r`), ready for three.js:
   * `sourceObject.matrix.fromArray(result.matrix)`.
   */
  matrix: Float32Array;
  /**
   * `matrix` at full (f64) precision, the same layout: use it when coordinates are large (e.g.
   * georeferenced scans given as `Float64Array`s), where float32 would round the translation.
   * three.js reads it the same way (`Matrix4.fromArray(result.matrix64)`).
   */
  matrix64: Float64Array;
  /**
   * The coarse estimate before ICP (network + GMR, or `initialTransform` with `network: false`);
   * same frames and layout as `matrix`.
   */
  networkMatrix: Float32Array;
  /** `networkMatrix` at full (f64) precision, like `matrix64`. */
  networkMatrix64: Float64Array;
  /** The start (of `RegisterOptions.starts`) whose refinement is `matrix`. */
  start: RegistrationStart;
  /**
   * Fraction of (voxelised) source points that have a target point within
   * `maxCorrespondenceDistance` under `matrix`, in [0, 1]. Right answers on partial,
   * independently sampled scans often score only 0.15-0.3: judge the result by `confidence`.
   */
  fitness: number;
  /** RMS distance of those inlier pairs, in your units (0 when there are none). */
  inlierRmse: number;
  /** ICP iterations over all stages of the chosen start's refinement (0 with `icp: "off"`). */
  iterations: number;
  /** True when the chosen start's last ICP stage met its convergence criteria (false with `icp: "off"`). */
  converged: boolean;
  /** The final max correspondence distance used, in your units (the default resolved). */
  maxCorrespondenceDistance: number;
  /** Time per stage, in milliseconds. */
  timingsMs: RegistrationTimings;
  /**
   * Things to know about this result (input resampled, low confidence, ...), as sentences. One
   * starting with `"low confidence"` comes with every result whose `confidence` is below 0.5.
   */
  warnings: string[];
  /**
   * An estimate of the probability that `matrix` is right (within the evaluation's recall
   * thresholds), in [0, 1]: a logistic model over `evidence`, calibrated on validation pairs
   * (the paper's protocol and pairs of any pose). Read it as "likely right" near 1, "likely
   * wrong" near 0; below 0.5 `warnings` says the alignment may be wrong. It judges the fit, so a
   * symmetric or featureless shape that fits in several poses lowers it (`evidence.ambiguity`).
   */
  confidence: number;
  /** The figures `confidence` is computed from, measured under `matrix`. */
  evidence: RegistrationEvidence;
  /** How many distinct starts were refined (after merging those that met); see `RegisterOptions.search`. */
  startsRefined: number;
}

/**
 * The evidence behind `RegistrationResult.confidence`, measured on the (voxelised) clouds under
 * the answer, at multiples of the final `maxCorrespondenceDistance` `d`.
 */
export interface RegistrationEvidence {
  /** Fraction of source points with a target point within `d` (in [0, 1]). */
  fitness: number;
  /** The same within `d / 2`. */
  fitnessTight: number;
  /** The same within `2 d`. */
  fitnessLoose: number;
  /** The same within `4 d`. */
  fitnessCoarse: number;
  /** Fraction of target points with a source point within `d`: the overlap measured the other way. */
  overlapReverse: number;
  /** Inlier RMSE at `d`, divided by `d` (0 without inliers). */
  rmseRatio: number;
  /**
   * How well the best *different* pose fits, as a fraction of the answer's fitness (the answer
   * turned 180 degrees about each principal axis of the moved source, each refined by a short
   * ICP), in [0, 2]; 0 when every one fell back onto the answer. Near 1 or above: the shape is
   * symmetric and the answer, though it fits, may not be the only one.
   */
  ambiguity: number;
}

/** How a weights file was made (its `provenance` metadata); `kind: "random"` means untrained. */
export interface ModelProvenance {
  /** `"random"` for an untrained deterministic initialisation, else how it was trained. */
  kind?: string;
  [key: string]: unknown;
}

/** The network sizes read from a weights file (the file stores them in snake_case; here camelCase). */
export interface ModelConfig {
  /** Preset the config started from (`"web"`, `"paper"`, `"tiny"` or a custom label). */
  preset: string;
  /** Network points per cloud, N (the default of `networkPoints`). */
  nPoints: number;
  /** Per-point feature width C; attention tokens are 2C wide. */
  featureDim: number;
  /** Attention heads. */
  heads: number;
  /** Hidden width of each attention block's feed-forward network. */
  ffnDim: number;
  /** ARPS layers, L. */
  layers: number;
  /** Top-H size of the `"top_h"` reference rule. */
  topH: number;
  /** Gaussians, J. */
  gaussians: number;
  /** Hidden widths of the position MLP. */
  posHidden: number[];
  /** Hidden width of the step-size MLP. */
  stepHidden: number;
  /** Hidden widths of the membership head. */
  headHidden: number[];
  /** Reference-point rule: the paper's top-H mean, or the differentiable softmax-weighted mean. */
  reference: "top_h" | "soft";
  /** Softmax temperature of the `"soft"` rule. */
  softTemperature: number;
  /** LayerNorm epsilon. */
  layerNormEps: number;
}
