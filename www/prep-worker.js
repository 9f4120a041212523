// The demo page's cloud store: a module worker that holds every point of the loaded scans, so the
// page's main thread never walks, copies or serialises a whole scan (www/prep.js is its promise
// API). A scan is float32 offsets from a float64 origin (what the engine's readPointCloud gives),
// so map-grid coordinates keep their digits, kept as read with a `scale` (a change of unit) that
// everything it hands out is multiplied by. Requests carry an `id`; replies echo it, or carry
// `error`.
//   { type: "store", key, points, origin, scale, maxDrawn, seed }  keeps the finite points under
//       `key`; replies { count, drawn, bounds, origin, dropped }: drawn = at most maxDrawn of them
//       (seeded stratified subsample, for the view), bounds = of all of them (null if none), both
//       as offsets from origin, all scaled; dropped = how many were non-finite
//   { type: "scale", key, scale, maxDrawn, seed }  a new scale; replies as "store" does
//   { type: "copy", key }                  -> { points, origin }  a fresh scaled copy, transferred
//                                              (for the engine)
//   { type: "drop", key }                  forgets the points (no reply)
import { bounds, decimate, finitePoints } from "./lib.js";

const clouds = new Map();

/** The scan stored under `key`: `{ points, origin, scale, box }` (`box`: bounds as read). */
function stored(key) {
  const cloud = clouds.get(key);
  if (!cloud) throw new Error(`no scan stored as ${JSON.stringify(key)}`);
  return cloud;
}

/** Multiplies packed xyz in place by `s` (nothing to do for 1); returns them. */
function scaled(points, s) {
  if (s !== 1) for (let i = 0; i < points.length; i++) points[i] *= s;
  return points;
}

/** What the page gets of a stored scan: its count, drawn subsample, bounds and origin, scaled. */
function summary({ points, origin, scale, box }, maxDrawn, seed) {
  const drawn = scaled(decimate(points, maxDrawn, seed), scale);
  const bounds = box && { min: box.min.map((v) => v * scale), max: box.max.map((v) => v * scale) };
  return { count: points.length / 3, drawn, bounds, origin: origin.map((v) => v * scale) };
}

/** `scale` checked: a finite number > 0 (1 when absent). */
function scaleOf(s) {
  if (s === undefined || s === null) return 1;
  if (!(Number.isFinite(s) && s > 0)) throw new Error(`a scale must be a finite number > 0, got ${s}`);
  return s;
}

self.addEventListener("message", ({ data }) => {
  const { id, type, key } = data;
  try {
    switch (type) {
      case "store": {
        const scale = scaleOf(data.scale);
        const { points, dropped } = finitePoints(data.points);
        const origin = data.origin ? Array.from(data.origin, Number) : [0, 0, 0];
        const cloud = { points, origin, scale, box: bounds(points) };
        clouds.set(key, cloud);
        const out = { ...summary(cloud, data.maxDrawn, data.seed), dropped };
        self.postMessage({ id, ...out }, [out.drawn.buffer]);
        return;
      }
      case "scale": {
        const cloud = stored(key);
        cloud.scale = scaleOf(data.scale);
        const out = summary(cloud, data.maxDrawn, data.seed);
        self.postMessage({ id, ...out }, [out.drawn.buffer]);
        return;
      }
      case "copy": {
        const { points, origin, scale } = stored(key);
        const copy = scaled(points.slice(), scale);
        self.postMessage({ id, points: copy, origin: origin.map((v) => v * scale) }, [copy.buffer]);
        return;
      }
      case "drop":
        clouds.delete(key);
        return;
      default:
        throw new Error(`unknown request ${JSON.stringify(type)}`);
    }
  } catch (e) {
    self.postMessage({ id, error: e instanceof Error ? e.message : String(e) });
  }
});
