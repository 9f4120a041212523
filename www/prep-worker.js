// The demo page's cloud store: a module worker that holds every point of the loaded scans, so the
// page's main thread never walks, copies or serialises a whole scan (www/prep.js is its promise
// API). A scan is float32 offsets from a float64 origin (what the engine's readPointCloud gives),
// so map-grid coordinates keep their digits. Requests carry an `id`; replies echo it, or carry
// `error`.
//   { type: "store", key, points, origin, maxDrawn, seed }  keeps the finite points under `key`;
//       replies { count, drawn, bounds, dropped }: drawn = at most maxDrawn of them (seeded
//       stratified subsample, for the view), bounds = of all of them (null if none), both as
//       offsets from the origin; dropped = how many were non-finite
//   { type: "copy", key }                  -> { points, origin }  a fresh copy of the points,
//                                              transferred (for the engine)
//   { type: "drop", key }                  forgets the points (no reply)
import { bounds, decimate, finitePoints } from "./lib.js";

const clouds = new Map();

/** The scan stored under `key`: `{ points, origin }`. */
function stored(key) {
  const cloud = clouds.get(key);
  if (!cloud) throw new Error(`no scan stored as ${JSON.stringify(key)}`);
  return cloud;
}

self.addEventListener("message", ({ data }) => {
  const { id, type, key } = data;
  try {
    switch (type) {
      case "store": {
        const { points, dropped } = finitePoints(data.points);
        const origin = data.origin ? Array.from(data.origin, Number) : [0, 0, 0];
        clouds.set(key, { points, origin });
        const drawn = decimate(points, data.maxDrawn, data.seed);
        const box = bounds(drawn.length === points.length ? drawn : points);
        self.postMessage({ id, count: points.length / 3, drawn, bounds: box, dropped }, [drawn.buffer]);
        return;
      }
      case "copy": {
        const { points, origin } = stored(key);
        const copy = points.slice();
        self.postMessage({ id, points: copy, origin }, [copy.buffer]);
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
