// The JS-only types of the package. The option, result and model types (`RegisterOptions`,
// `RegistrationResult`, `ModelConfig`, ...) are generated from the Rust types into
// js/arps-contract.d.ts (scripts/gen-types.sh); both files are appended to pkg/arps.d.ts.

/**
 * A point cloud, packed xyz `[x0, y0, z0, x1, ...]` (at least 16 finite points):
 * - a `Float32Array`, used as is;
 * - a `Float64Array`: for large coordinates (e.g. georeferenced scans). The engine works on
 *   float32 offsets from the centre of the cloud's bulk (a stray point far from the rest left
 *   out of it), and the result's `T_target_source` is mapped back in float64, exact in your frame;
 * - `{ points, origin }`: float32 `points` relative to `origin` (`[x, y, z]`, float64), e.g. what
 *   `readPointCloud` returns; the result is in the frame of `points + origin`;
 * - an `Array` of numbers: doubles, read as a `Float64Array` is.
 */
export type CloudInput = Float32Array | Float64Array | number[] | CloudWithOrigin;

/**
 * A cloud as float32 offsets from a float64 origin: point `i` is `origin + points[i]` (what
 * `readPointCloud` returns, and a `CloudInput`).
 */
export interface CloudWithOrigin {
  /** Packed xyz offsets from `origin`, `[x0, y0, z0, x1, ...]`. */
  points: Float32Array;
  /** `[x, y, z]`, in your units (float64): an array or a typed array of 3 finite numbers. */
  origin: readonly number[] | Float64Array | Float32Array;
}

/** What `rigidFromPairs` returns: the motion that best maps the paired points, and how well. */
export interface PairsFit {
  /** The rigid `T_target_source`, 16 numbers, column-major (ready for `initialTransform`). */
  T_target_source: number[];
  /** The RMS distance between the pairs under it, in the clouds' units. */
  rmse: number;
}

/** How a weights file was made (its `provenance` metadata); `kind: "random"` means untrained. */
export interface ModelProvenance {
  /** `"random"` for an untrained deterministic initialisation, else how it was trained. */
  kind?: string;
  [key: string]: unknown;
}
