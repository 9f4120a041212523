// Pure helpers of the demo page (no DOM, no three.js): matrices, the PLY writer, the example pair.
// Matrices are 4x4 column-major arrays (element (row r, col c) at index c * 4 + r), like the
// package's `result.T_target_source` and three.js `Matrix4.elements`.

/** Four row-major rows of a column-major 4x4. */
export function rowMajor(m) {
  return [0, 1, 2, 3].map((r) => [0, 1, 2, 3].map((c) => m[c * 4 + r]));
}

/** Rotation angle of a rigid transform's rotation part, in degrees. */
export function rotationAngleDeg(m) {
  const cos = (m[0] + m[5] + m[10] - 1) / 2;
  return (Math.acos(Math.min(1, Math.max(-1, cos))) * 180) / Math.PI;
}

/** a * b, both column-major 4x4. */
export function multiply(a, b) {
  const out = new Float64Array(16);
  for (let r = 0; r < 4; r++)
    for (let c = 0; c < 4; c++) {
      let s = 0;
      for (let k = 0; k < 4; k++) s += a[k * 4 + r] * b[c * 4 + k];
      out[c * 4 + r] = s;
    }
  return out;
}

/** Inverse of a rigid transform (R^T, -R^T t). */
export function invertRigid(m) {
  const out = new Float64Array(16);
  for (let r = 0; r < 3; r++) {
    for (let c = 0; c < 3; c++) out[c * 4 + r] = m[r * 4 + c];
    out[12 + r] = -(m[r * 4] * m[12] + m[r * 4 + 1] * m[13] + m[r * 4 + 2] * m[14]);
  }
  out[15] = 1;
  return out;
}

/** Rigid transform: rotation of `deg` degrees about `axis`, then translation `t`. */
export function rigid(axis, deg, t) {
  const n = Math.hypot(...axis);
  const [x, y, z] = axis.map((v) => v / n);
  const a = (deg * Math.PI) / 180;
  const c = Math.cos(a);
  const s = Math.sin(a);
  const C = 1 - c;
  // Column-major.
  return Float64Array.from([
    c + x * x * C, y * x * C + z * s, z * x * C - y * s, 0,
    x * y * C - z * s, c + y * y * C, z * y * C + x * s, 0,
    x * z * C + y * s, y * z * C - x * s, c + z * z * C, 0,
    t[0], t[1], t[2], 1,
  ]);
}

/** Packed xyz points mapped through a column-major rigid transform (a new Float32Array). */
export function transformPoints(points, m) {
  const out = new Float32Array(points.length);
  for (let i = 0; i < points.length; i += 3) {
    const x = points[i];
    const y = points[i + 1];
    const z = points[i + 2];
    out[i] = m[0] * x + m[4] * y + m[8] * z + m[12];
    out[i + 1] = m[1] * x + m[5] * y + m[9] * z + m[13];
    out[i + 2] = m[2] * x + m[6] * y + m[10] * z + m[14];
  }
  return out;
}

/**
 * The column-major rigid transform `m` (between absolute frames) acting on points stored as
 * offsets from `from` and giving offsets from `to`: `T(-to) m T(from)`, in f64 (its translation
 * `R from + t - to` stays small when the frames are near each other, whatever their coordinates).
 */
export function relativeTo(m, from, to) {
  const out = Float64Array.from(m);
  for (let r = 0; r < 3; r++) out[12 + r] = m[r] * from[0] + m[4 + r] * from[1] + m[8 + r] * from[2] + m[12 + r] - to[r];
  return out;
}

/** True when `origin` (`[x, y, z]`, or null) is not the zero vector. */
export function hasOrigin(origin) {
  return !!origin && (origin[0] !== 0 || origin[1] !== 0 || origin[2] !== 0);
}

/** Drops points with a NaN or infinite coordinate; returns `{ points, dropped }`. */
export function finitePoints(points) {
  let bad = 0;
  for (let i = 0; i < points.length; i += 3)
    if (!(Number.isFinite(points[i]) && Number.isFinite(points[i + 1]) && Number.isFinite(points[i + 2]))) bad++;
  if (bad === 0) return { points, dropped: 0 };
  const out = new Float32Array(points.length - bad * 3);
  let j = 0;
  for (let i = 0; i < points.length; i += 3) {
    if (!(Number.isFinite(points[i]) && Number.isFinite(points[i + 1]) && Number.isFinite(points[i + 2]))) continue;
    out[j++] = points[i];
    out[j++] = points[i + 1];
    out[j++] = points[i + 2];
  }
  return { points: out, dropped: bad };
}

/** A binary little-endian PLY file (float x, y, z) of packed xyz points. */
export function writePly(points, comment = "") {
  const n = points.length / 3;
  const header =
    "ply\nformat binary_little_endian 1.0\n" +
    (comment ? `comment ${comment.replace(/\s+/g, " ")}\n` : "") +
    `element vertex ${n}\nproperty float x\nproperty float y\nproperty float z\nend_header\n`;
  const head = new TextEncoder().encode(header);
  const bytes = new Uint8Array(head.length + n * 12);
  bytes.set(head, 0);
  const view = new DataView(bytes.buffer, head.length);
  for (let i = 0; i < points.length; i++) view.setFloat32(i * 4, points[i], true);
  return bytes;
}

/** Deterministic pseudo-random numbers in [0, 1) (mulberry32). */
export function random(seed) {
  let a = seed >>> 0;
  return () => {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

/** `count` points sampled uniformly (by area) on a triangle mesh. */
export function sampleMesh(positions, cells, count, rand) {
  const cum = new Float64Array(cells.length);
  let total = 0;
  cells.forEach(([i, j, k], f) => {
    const [a, b, c] = [positions[i], positions[j], positions[k]];
    const u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    const v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    total += 0.5 * Math.hypot(u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]);
    cum[f] = total;
  });
  const out = new Float32Array(count * 3);
  for (let n = 0; n < count; n++) {
    const x = rand() * total;
    let lo = 0;
    let hi = cells.length - 1;
    while (lo < hi) {
      const mid = (lo + hi) >> 1;
      if (cum[mid] < x) lo = mid + 1;
      else hi = mid;
    }
    const [a, b, c] = cells[lo].map((i) => positions[i]);
    let r1 = rand();
    let r2 = rand();
    if (r1 + r2 > 1) [r1, r2] = [1 - r1, 1 - r2];
    for (let d = 0; d < 3; d++) out[n * 3 + d] = a[d] + r1 * (b[d] - a[d]) + r2 * (c[d] - a[d]);
  }
  return out;
}

/** The points whose projection on `dir` is at most the `keep` quantile (a half-space crop). */
export function crop(points, dir, keep) {
  const n = points.length / 3;
  const proj = new Float64Array(n);
  for (let i = 0; i < n; i++) proj[i] = points[i * 3] * dir[0] + points[i * 3 + 1] * dir[1] + points[i * 3 + 2] * dir[2];
  const cut = Float64Array.from(proj).sort()[Math.min(n - 1, Math.floor(keep * n))];
  const out = [];
  for (let i = 0; i < n; i++) if (proj[i] <= cut) out.push(points[i * 3], points[i * 3 + 1], points[i * 3 + 2]);
  return { points: Float32Array.from(out), dir, cut };
}

/** Parses the npm `bunny` package's index.js (lines `exports.positions=[...]`, `exports.cells=[...]`). */
export function parseBunny(text) {
  const grab = (name) => {
    const start = text.indexOf(`exports.${name}=`);
    if (start < 0) throw new Error(`bunny: no ${name} in the module`);
    const body = text.slice(start + name.length + 9).split(/\n|;/, 1)[0];
    return JSON.parse(body);
  };
  return { positions: grab("positions"), cells: grab("cells") };
}

/** The example's known motion `T_target_source`: 20 degrees about a tilted axis plus a shift. */
export const EXAMPLE_TRUTH = rigid([0.3, 1, 0.2], 20, [0.9, -0.4, 0.5]);

/**
 * Two partial, offset views of a mesh: each is an independent surface sample cropped by a
 * different half-space (about 85% of the surface each, about 75% shared); the source is then
 * moved by the inverse of `EXAMPLE_TRUTH`, so the right answer is `EXAMPLE_TRUTH`.
 */
export function makeExample({ positions, cells }, count = 6000, seed = 1) {
  const rand = random(seed);
  const a = crop(sampleMesh(positions, cells, count, rand), [0.8, 0, 0.6], 0.85);
  const b = crop(sampleMesh(positions, cells, count, rand), [-0.6, 0.2, 0.77], 0.85);
  const source = transformPoints(a.points, invertRigid(EXAMPLE_TRUTH));
  // Fraction of the source's surface that the target also saw.
  let shared = 0;
  for (let i = 0; i < a.points.length; i += 3) {
    const p = a.points;
    if (p[i] * b.dir[0] + p[i + 1] * b.dir[1] + p[i + 2] * b.dir[2] <= b.cut) shared++;
  }
  return { source, target: b.points, truth: EXAMPLE_TRUTH, overlap: shared / (a.points.length / 3) };
}

/**
 * The poses a result offers: its answer, then its `alternatives` (other poses that fit about as
 * well, best fitting first), each `{ label, T_target_source, fitness, inlierRmse }` with the
 * transform column-major as in the result; `label` is `"answer"` or `"alternative k"` (from 1).
 */
export function posesOf(result) {
  const answer = { label: "answer", T_target_source: result.T_target_source, fitness: result.fitness, inlierRmse: result.inlierRmse };
  const others = (result.alternatives ?? []).map((a, i) => ({
    label: `alternative ${i + 1}`,
    T_target_source: a.T_target_source,
    fitness: a.fitness,
    inlierRmse: a.inlierRmse,
  }));
  return [answer, ...others];
}

/**
 * A result's `confidence` (the engine's estimate, in [0, 1], that the answer is right) in words:
 * `{ words, level }`, `level` one of `"right"` (>= 0.8), `"uncertain"` (>= 0.5) and `"wrong"`
 * (below 0.5, where the engine also warns; it warns at 0.5 too when another pose fits about as
 * well), e.g. `"likely right (confidence 0.93)"`. Below 0.8 with `alternatives` (the number of
 * other poses that fit about as well), "ambiguous": the answer may be right, or one of them.
 */
export function confidenceWords(confidence, alternatives = 0) {
  if (!Number.isFinite(confidence)) return { words: "unknown confidence", level: "uncertain" };
  const figure = `(confidence ${confidence.toFixed(2)})`;
  if (confidence >= 0.8) return { words: `likely right ${figure}`, level: "right" };
  const level = confidence >= 0.5 ? "uncertain" : "wrong";
  // other poses fit about as well (a symmetric shape): the answer may be right, or one of them
  if (alternatives > 0) return { words: `ambiguous ${figure}: ${alternatives} other pose${alternatives === 1 ? "" : "s"} fit about as well`, level };
  return { words: `${confidence >= 0.5 ? "uncertain" : "likely wrong"} ${figure}`, level };
}

/**
 * At most `max` of the packed xyz `points` for drawing: all of them when there are few enough,
 * else a stratified random subsample (the i-th point drawn from the i-th of `max` equal runs of
 * the input, at a seeded random offset), so scan-line order does not alias. Points with a
 * non-finite coordinate are skipped. Always a new array (the input can be transferred after).
 */
export function decimate(points, max, seed = 0) {
  const n = points.length / 3;
  const take = Math.min(n, Math.max(0, Math.floor(max)));
  const out = new Float32Array(take * 3);
  const rand = random(seed);
  let k = 0;
  for (let i = 0; i < take; i++) {
    const j = take === n ? i : Math.min(n - 1, Math.floor(((i + rand()) * n) / take));
    const x = points[j * 3];
    const y = points[j * 3 + 1];
    const z = points[j * 3 + 2];
    if (!(Number.isFinite(x) && Number.isFinite(y) && Number.isFinite(z))) continue;
    out[k++] = x;
    out[k++] = y;
    out[k++] = z;
  }
  return k === out.length ? out : out.slice(0, k);
}

/** Axis-aligned bounds `{ min: [x, y, z], max: [x, y, z] }` of the finite points; `null` if none. */
export function bounds(points) {
  let x0 = Infinity, y0 = Infinity, z0 = Infinity, x1 = -Infinity, y1 = -Infinity, z1 = -Infinity;
  for (let i = 0; i < points.length; i += 3) {
    const x = points[i];
    const y = points[i + 1];
    const z = points[i + 2];
    if (!(Number.isFinite(x) && Number.isFinite(y) && Number.isFinite(z))) continue;
    if (x < x0) x0 = x;
    if (x > x1) x1 = x;
    if (y < y0) y0 = y;
    if (y > y1) y1 = y;
    if (z < z0) z0 = z;
    if (z > z1) z1 = z;
  }
  return x0 <= x1 ? { min: [x0, y0, z0], max: [x1, y1, z1] } : null;
}

/** The bounds of `b`'s eight corners mapped through the column-major rigid transform `m`. */
export function transformBounds(b, m) {
  const corners = new Float32Array(24);
  for (let c = 0; c < 8; c++)
    for (let d = 0; d < 3; d++) corners[c * 3 + d] = (c >> d) & 1 ? b.max[d] : b.min[d];
  return bounds(transformPoints(corners, m));
}

/** The smallest bounds holding every one of `list` (`null` entries skipped); `null` if none. */
export function unionBounds(list) {
  let out = null;
  for (const b of list) {
    if (!b) continue;
    out = out
      ? { min: out.min.map((v, d) => Math.min(v, b.min[d])), max: out.max.map((v, d) => Math.max(v, b.max[d])) }
      : { min: [...b.min], max: [...b.max] };
  }
  return out;
}

/**
 * Parameters of a network with these sizes (a `modelConfig` from the engine), by the same
 * arithmetic as the engine's `ModelConfig::parameter_count`: L ARPS layers (position MLP, two
 * attention blocks on 2C-wide tokens, output, soft-reference score, step MLP) and the membership
 * head.
 */
export function parameterCount(config) {
  const linear = (i, o) => i * o + o;
  const mlp = (first, hidden, last) => {
    let prev = first;
    let sum = 0;
    for (const h of [...hidden, last]) {
      sum += linear(prev, h);
      prev = h;
    }
    return sum;
  };
  const c = config.featureDim;
  const d = 2 * c;
  const block = 4 * linear(d, d) + 4 * d + linear(d, config.ffnDim) + linear(config.ffnDim, d);
  const score = config.reference === "soft" ? linear(c, 1) : 0;
  const layer =
    mlp(3, config.posHidden, c) + 2 * block + linear(d, c) + score + linear(3 + c, config.stepHidden) + linear(config.stepHidden, 1);
  return config.layers * layer + mlp(2 * c, config.headHidden, config.gaussians);
}

const STORED = { f16: "16-bit floats", f32: "32-bit floats", i8: "8-bit integers", int8: "8-bit integers", q8: "8-bit integers" };
const word = (v) => (typeof v === "string" && /^[\w.+-]{1,40}$/.test(v) ? v : null);
const count = (v) => (Number.isFinite(v) && v >= 0 ? Math.round(v).toLocaleString("en") : null);

/**
 * The engine's model in words, for the engine badge: `{ label, about, untrained }`. `label` is
 * short (name and size); `about` says what the network is and how it was trained, from the
 * weights' provenance and config (only counts and short names, never paths or raw JSON).
 */
export function modelSummary(provenance, config) {
  const p = provenance && typeof provenance === "object" ? provenance : {};
  if (p.kind === "random") {
    return {
      label: "untrained placeholder model",
      about: "The network's weights are an untrained placeholder: ICP and the global search do the work.",
      untrained: true,
    };
  }
  const name = word(config?.preset) ?? "custom";
  let params = null;
  try {
    const n = parameterCount(config);
    if (Number.isFinite(n) && n > 0) params = n;
  } catch {
    /* a config without the sizes: no count */
  }
  const millions = params ? `${(params / 1e6).toFixed(2)} M parameters` : null;
  const label = `model “${name}”${millions ? ` · ${millions}` : ""}`;
  const sentences = [];
  const run = word(p.run);
  const what = [];
  if (params) what.push(`${(params / 1e6).toFixed(2)} million parameters`);
  if (config?.layers && config?.featureDim)
    what.push(`${config.layers} attention layers on ${2 * config.featureDim}-wide tokens, ${config.gaussians} Gaussians`);
  if (config?.nPoints) what.push(`${config.nPoints} points per scan into the network`);
  const stored = STORED[p.stored_as] ?? null;
  sentences.push(
    `Model “${name}”${run ? ` (run ${run})` : ""}${what.length ? `: ${what.join("; ")}` : ""}${stored ? `, weights stored as ${stored}` : ""}.`,
  );
  const steps = count(p.step);
  const pairs = count(p.pairs_seen);
  const hours = Number.isFinite(p.run_total?.wall_clock_s ?? p.wall_clock_s) ? (p.run_total?.wall_clock_s ?? p.wall_clock_s) / 3600 : null;
  const sessions = count(p.run_total?.sessions);
  if (steps || pairs) {
    const data = [];
    if (p.data?.procedural) data.push("procedurally generated shapes");
    const meshes = count(p.data?.bank_meshes?.train);
    if (meshes && meshes !== "0") data.push(`a bank of ${meshes} meshes`);
    const trainer = word(String(p.trainer ?? p.exported_by ?? "").split(" ")[0]);
    sentences.push(
      `Trained${trainer ? ` with ${trainer}` : ""}${steps ? ` for ${steps} steps` : ""}${pairs ? ` on ${pairs} synthetic partial-scan pairs` : ""}` +
        `${data.length ? ` (${data.join(" and ")})` : ""}` +
        `${hours ? `, about ${hours.toFixed(1)} hours of CPU time${sessions ? ` over ${sessions} sessions` : ""}` : ""}.`,
    );
  } else {
    sentences.push("No training record came with these weights.");
  }
  return { label, about: sentences.join(" "), untrained: false };
}
