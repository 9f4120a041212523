// Promise API of the page's cloud store (prep-worker.js): every point of each loaded scan lives
// there; the main thread gets a subsample to draw, bounds, and transferable copies for the engine.
// The worker starts on the first request; after a crash the next request starts a new (empty) one.

let worker = null;
let nextId = 1;
const pending = new Map();

function start() {
  const w = new Worker(new URL("./prep-worker.js", import.meta.url), { type: "module", name: "arps-page-store" });
  w.addEventListener("message", ({ data }) => {
    const p = pending.get(data.id);
    if (!p) return;
    pending.delete(data.id);
    if (data.error) p.reject(new Error(data.error));
    else p.resolve(data);
  });
  w.addEventListener("error", (event) => {
    event.preventDefault();
    const error = new Error(`the page's scan store failed: ${event.message || "unknown error"}; load the scans again`);
    for (const p of pending.values()) p.reject(error);
    pending.clear();
    w.terminate();
    if (worker === w) worker = null;
  });
  return w;
}

function request(message, transfer = []) {
  worker ??= start();
  const id = nextId++;
  return new Promise((resolve, reject) => {
    pending.set(id, { resolve, reject });
    worker.postMessage({ ...message, id }, transfer);
  });
}

/**
 * Stores the cloud `{ points, origin }` under `key`, without its non-finite points: `points` packed
 * xyz offsets from `origin` (`[x, y, z]`, f64; null for zero), transferred, so detached here
 * afterwards; `scale` (a change of unit, default 1) multiplies all it hands out. Resolves to
 * `{ count, drawn, bounds, origin, dropped }`: `drawn` at most `maxDrawn` of the points (a seeded
 * stratified subsample) for the view, `bounds` `{ min, max }` of all of them (`null` when none is
 * finite), both as offsets from `origin`, all scaled; `dropped` how many were non-finite.
 */
export function storeCloud(key, { points, origin = null }, { scale = 1, maxDrawn, seed = 0 }) {
  const o = origin ? Array.from(origin, Number) : null;
  return request({ type: "store", key, points, origin: o, scale, maxDrawn, seed }, [points.buffer]);
}

/** Sets the scale of the cloud under `key`; resolves as `storeCloud` does (without `dropped`). */
export function rescaleCloud(key, { scale, maxDrawn, seed = 0 }) {
  return request({ type: "scale", key, scale, maxDrawn, seed });
}

/** A fresh copy of the cloud stored under `key`, scaled, `{ points, origin }` (yours to transfer). */
export async function copyCloud(key) {
  const { points, origin } = await request({ type: "copy", key });
  return { points, origin };
}

/** Forgets the points stored under `key`. */
export function dropCloud(key) {
  if (worker) worker.postMessage({ type: "drop", key, id: 0 });
}
