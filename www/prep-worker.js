// The demo page's cloud store: a module worker that holds every point of the loaded scans, so the
// page's main thread never walks, copies or serialises a whole scan (www/prep.js is its promise
// API). Requests carry an `id`; replies echo it, or carry `error`.
//   { type: "store", key, points, maxDrawn, seed }  keeps the finite points under `key`; replies
//       { count, drawn, bounds, dropped }: drawn = at most maxDrawn of them (seeded stratified
//       subsample, for the view), bounds = of all of them (null if none), dropped = non-finite
//   { type: "copy", key }                  -> { points }  a fresh copy, transferred (for the engine)
//   { type: "ply", key, matrix, comment }  -> { bytes }   binary PLY of the points mapped through
//                                                         the column-major matrix
//   { type: "drop", key }                  forgets the points (no reply)
import { bounds, decimate, finitePoints, transformPoints, writePly } from "./lib.js";

const clouds = new Map();

function stored(key) {
  const points = clouds.get(key);
  if (!points) throw new Error(`no scan stored as ${JSON.stringify(key)}`);
  return points;
}

self.addEventListener("message", ({ data }) => {
  const { id, type, key } = data;
  try {
    switch (type) {
      case "store": {
        const { points, dropped } = finitePoints(data.points);
        clouds.set(key, points);
        const drawn = decimate(points, data.maxDrawn, data.seed);
        const box = bounds(drawn.length === points.length ? drawn : points);
        self.postMessage({ id, count: points.length / 3, drawn, bounds: box, dropped }, [drawn.buffer]);
        return;
      }
      case "copy": {
        const points = stored(key).slice();
        self.postMessage({ id, points }, [points.buffer]);
        return;
      }
      case "ply": {
        const bytes = writePly(transformPoints(stored(key), data.matrix), data.comment);
        self.postMessage({ id, bytes }, [bytes.buffer]);
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
