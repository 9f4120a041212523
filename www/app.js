// The arps demo page: load two scans (parsed in the engine's worker, readied for drawing in the
// page's worker), align them in the engine's worker, show the result in three.js. The main thread
// never walks a whole scan. Each scan is float32 offsets from a float64 origin, from reading to
// the engine, the view and the download, so georeferenced surveys keep their digits. Test hooks: #source-file, #target-file, #align, #result (the result
// as JSON), #verdict (the confidence in words), #alternatives (buttons for the other poses that fit
// about as well, when there are some), #error (the message).
import { createWorkerRegistrar, STAGES } from "../pkg/worker-client.js";
import {
  confidenceWords,
  hasOrigin,
  invertRigid,
  makeExample,
  modelSummary,
  multiply,
  parseBunny,
  posesOf,
  rotationAngleDeg,
  rowMajor,
} from "./lib.js";
import { copyCloud, dropCloud, rescaleCloud, storeCloud } from "./prep.js";
import { MAX_DRAWN, createView } from "./view.js";

const $ = (id) => document.getElementById(id);

/** Points drawn over the surface of a mesh file (OBJ, OFF, STL, glTF/GLB, PLY with faces). */
const MESH_SURFACE_POINTS = 200_000;

// ---- state --------------------------------------------------------------------------------

const state = {
  // { key (its points in the page's store, www/prep.js), count, bounds: { min, max } (offsets from
  // origin), origin: [x, y, z], name, note }; the main thread holds no whole scan
  source: null,
  target: null,
  truth: null, // the example's known T_target_source (column-major), if the example is loaded
  result: null, // the last RegistrationResult
  pose: 0, // the pose of the result shown: 0 its answer, k its alternative k (posesOf)
  busy: false,
  view: "before",
};

// ---- the engine (a worker client; it replaces its worker itself after a crash, a trap or a cancel) ----

let engine = null;
function getEngine() {
  if (!engine) {
    setBadge("loading the engine…", "");
    engine = createWorkerRegistrar().then(
      (arps) => {
        const model = modelSummary(arps.provenance, arps.modelConfig);
        setBadge(`engine ready · ${model.label}`, model.untrained ? "warn" : "ok", model.about);
        return arps;
      },
      (e) => {
        engine = null;
        setBadge("engine failed to load", "bad");
        throw e;
      },
    );
  }
  return engine;
}

/** The engine badge: `text` on it, `about` in its tooltip and in the panel it opens. */
function setBadge(text, kind, about = "") {
  const b = $("engine-status");
  b.textContent = text;
  b.className = `badge ${kind}`;
  b.title = about;
  $("engine-about").textContent = about;
}

// ---- errors and progress ------------------------------------------------------------------

function showError(message) {
  $("error").textContent = message;
  $("error").hidden = false;
}

function clearError() {
  $("error").textContent = "";
  $("error").hidden = true;
}

let timer = 0;
function startProgress() {
  const t0 = performance.now();
  $("progress").hidden = false;
  setStage("preparing");
  clearInterval(timer);
  timer = setInterval(() => {
    $("elapsed").textContent = `${((performance.now() - t0) / 1000).toFixed(1)} s`;
  }, 100);
}

function setStage(stage) {
  const at = STAGES.indexOf(stage);
  for (const li of $("stages").children) {
    const i = STAGES.indexOf(li.dataset.stage);
    li.className = i === at ? "current" : i < at ? "past" : "";
  }
}

function stopProgress() {
  clearInterval(timer);
  $("progress").hidden = true;
}

function updateButtons() {
  const reading = loading.source || loading.target;
  $("align").disabled = state.busy || reading || !state.source || !state.target;
  // why Align is off, on hover
  $("align").title = state.busy
    ? "Working…"
    : reading
      ? "Reading a scan…"
      : !state.source && !state.target
        ? "Load a source and a target scan first"
        : !state.source
          ? "Load a source scan first"
          : !state.target
            ? "Load a target scan first"
            : "";
  $("example").disabled = state.busy;
  $("source-file").disabled = state.busy;
  $("target-file").disabled = state.busy;
  $("source-unit").disabled = state.busy;
  $("target-unit").disabled = state.busy;
  $("source-scan").disabled = state.busy;
  $("target-scan").disabled = state.busy;
  $("view-after").disabled = !state.result;
}

// ---- loading scans ------------------------------------------------------------------------

const loads = { source: 0, target: 0 }; // the latest load of each slot wins
const loading = { source: false, target: false }; // a slot reading a file (Align waits)

const count = (n) => n.toLocaleString("en");
/** `n` points, in words ("1 point", "2,000 points"). */
const points = (n) => `${count(n)} ${n === 1 ? "point" : "points"}`;

/** An origin in words: its coordinates to a tenth of a unit. */
const place = (origin) => `(${Array.from(origin, (v) => v.toLocaleString("en", { maximumFractionDigits: 1 })).join(", ")})`;

/** The units the page offers for each scan: name and metres per unit (the options' values). */
const UNITS = [
  ["m", 1],
  ["cm", 0.01],
  ["mm", 0.001],
  ["in", 0.0254],
  ["ft", 0.3048],
];
for (const id of ["source-unit", "target-unit"]) {
  $(id).replaceChildren(...UNITS.map(([name, metres]) => new Option(name, String(metres), metres === 1, metres === 1)));
}

/** How many target units one source unit is (the #source-unit and #target-unit choice). */
function sourceScale() {
  return Number($("source-unit").value) / Number($("target-unit").value);
}

/**
 * The page's cloud `{ key, count, drawn, bounds, origin, name, note, dropped, scale, file }` from
 * the store's reply `ready` for `key` (`drawn`: the view's subsample; `scale`: the unit change
 * applied; `file`: the `File` it was read from, if any).
 */
function pageCloud(key, ready, name, scale, dropped, file = null) {
  const notes = [];
  if (ready.drawn.length / 3 < ready.count) notes.push(`${count(ready.drawn.length / 3)} drawn`);
  if (dropped) notes.push(`${count(dropped)} non-finite dropped`);
  if (scale !== 1) notes.push(`scaled ×${fmt(scale)} into the target's unit`);
  if (hasOrigin(ready.origin)) notes.push(`about ${place(ready.origin)}`);
  const { count: n, drawn, bounds, origin } = ready;
  return { key, count: n, drawn, bounds, origin, name, note: notes.join(" · "), dropped, scale, file };
}

/**
 * Hands `cloud` (`{ points, origin }`, points transferred) to the page's store under a key of
 * this load (a source scaled into the target's unit); resolves to the page's cloud (`pageCloud`).
 */
async function readyCloud(cloud, name, which, token, file = null) {
  const key = `${which}#${token}`;
  const scale = which === "source" ? sourceScale() : 1;
  const ready = await storeCloud(key, cloud, { scale, maxDrawn: MAX_DRAWN, seed: which === "source" ? 1 : 2 });
  if (!ready.bounds) {
    dropCloud(key);
    throw new Error("the file holds no (finite) points");
  }
  return pageCloud(key, ready, name, scale, ready.dropped, file);
}

/** After a change of units: the source, rescaled in the store, drawn again (any result cleared). */
async function rescaleSource() {
  const source = state.source;
  if (!source || state.busy) return;
  const token = loads.source;
  const scale = sourceScale();
  try {
    const ready = await rescaleCloud(source.key, { scale, maxDrawn: MAX_DRAWN, seed: 1 });
    if (token !== loads.source || state.source !== source) return;
    setCloud("source", pageCloud(source.key, ready, source.name, scale, source.dropped, source.file));
  } catch (e) {
    showError(`Could not rescale ${source.name}: ${e?.message ?? e}`);
  }
}

/**
 * The #source-scan / #target-scan choice for slot `which`: shown, with one option per scan and
 * one for all of them, when its file is an E57 file of several scans (`scans`: `listScans`'s
 * answer); else hidden. `scan`: the one read (`null`: all).
 */
function showScans(which, scans, scan) {
  const select = $(`${which}-scan`);
  $(`${which}-scan-field`).hidden = scans.length < 2;
  const name = (s, k) => `${k + 1}: ${s.name ?? `scan ${k + 1}`} (${points(s.records)})`;
  select.replaceChildren(
    new Option(`all ${scans.length} scans`, "", scan === null, scan === null),
    ...scans.map((s, k) => new Option(name(s, k), String(k), k === scan, k === scan)),
  );
}

/**
 * Reads `file` into slot `which`: all of it, or of an E57 file of several scans only scan number
 * `scan` (0-based; the slot's scan choice then lists them).
 */
async function loadFile(which, file, scan = null) {
  if (!file || state.busy) return;
  const token = ++loads[which];
  // the scan loaded before stays until this one is ready (a bad file does not throw it away)
  const previous = state[which];
  clearError();
  loading[which] = true;
  updateButtons();
  if (scan === null) showScans(which, [], null);
  $(`${which}-info`).textContent = `reading ${file.name}…`;
  let scans = [];
  try {
    const bytes = new Uint8Array(await file.arrayBuffer());
    const arps = await getEngine();
    // A mesh (a CAD model, say) is read as points spread over its surface, not its vertices,
    // which sit on its edges and corners; a point file is read as it is. Coordinates far from
    // zero (a map grid) come as offsets from an origin, in f64.
    const options = { surfacePoints: MESH_SURFACE_POINTS, scan };
    const parsed = await arps.readPointCloud(bytes, file.name, options, { transfer: true });
    if (token !== loads[which]) return;
    // (said now rather than at Align)
    const n = parsed.points.length / 3;
    if (n < 16) throw new Error(`it holds ${points(n)}; a registration needs at least 16`);
    if (/\.e57$/i.test(file.name)) {
      // an E57 file's scans, from its XML section (the bytes read again: the first went over)
      scans = await arps.listScans(new Uint8Array(await file.arrayBuffer()), file.name, { transfer: true });
      if (token !== loads[which]) return;
      showScans(which, scans, scan);
    }
    $(`${which}-info`).textContent = `${file.name}: preparing ${points(parsed.points.length / 3)}…`;
    const name = scan === null ? file.name : `${file.name}, scan ${scan + 1}`;
    const cloud = await readyCloud(parsed, name, which, token, file);
    if (token !== loads[which]) return dropCloud(cloud.key);
    cloud.scan = scan;
    cloud.scans = scans;
    setCloud(which, cloud);
  } catch (e) {
    if (token !== loads[which]) return;
    showScans(which, previous?.scans ?? [], previous?.scan ?? null);
    $(`${which}-info`).textContent = slotText(previous);
    showError(`Could not read ${file.name}: ${e?.message ?? e}${previous ? ` (${previous.name} stays loaded)` : ""}`);
  } finally {
    if (token === loads[which]) {
      loading[which] = false;
      updateButtons();
    }
  }
}

/** What a slot says of its cloud (or that it has none). */
function slotText(cloud) {
  return cloud ? `${cloud.name} · ${points(cloud.count)}${cloud.note ? ` · ${cloud.note}` : ""}` : "drop a file or click to choose";
}

/** Puts `cloud` (or nothing) in slot `which`: the store forgets the old one, the view draws the new. */
function setCloud(which, cloud) {
  if (state[which] && state[which].key !== cloud?.key) dropCloud(state[which].key);
  state[which] = cloud;
  state.result = null;
  state.truth = null;
  $(`${which}-info`).textContent = slotText(cloud);
  $(`${which}-drop`).classList.toggle("loaded", !!cloud);
  showResult(null);
  view.setAligned(null);
  view.setCloud(which, cloud); // hands cloud.drawn over to the view
  if (cloud) delete cloud.drawn;
  $("empty").hidden = !!(state.source || state.target);
  setView("before");
  view.fit();
  updateButtons();
}

async function loadExample() {
  if (state.busy) return;
  clearError();
  try {
    const response = await fetch(new URL("../node_modules/bunny/index.js", import.meta.url));
    if (!response.ok) throw new Error(`HTTP ${response.status} fetching the bunny mesh`);
    const example = makeExample(parseBunny(await response.text()));
    const tokens = [++loads.source, ++loads.target];
    const source = await readyCloud({ points: example.source }, "bunny, view A (moved)", "source", tokens[0]);
    const target = await readyCloud({ points: example.target }, "bunny, view B", "target", tokens[1]);
    if (tokens[0] !== loads.source || tokens[1] !== loads.target) {
      dropCloud(source.key);
      dropCloud(target.key);
      return;
    }
    for (const which of ["source", "target"]) showScans(which, [], null);
    setCloud("source", source);
    setCloud("target", target);
    state.truth = example.truth;
  } catch (e) {
    showError(`Could not make the example: ${e?.message ?? e}`);
  }
}

// ---- aligning -----------------------------------------------------------------------------

function readOptions() {
  const options = { icp: $("icp").value, search: $("search").value };
  const up = $("up").value;
  if (up !== "") options.up = up.split(",").map(Number);
  const share = $("source-overlap").value;
  if (share !== "") options.sourceOverlap = Number(share);
  const dist = $("max-distance").value.trim();
  if (dist !== "") {
    const d = Number(dist);
    if (!(d > 0)) throw new Error("Max correspondence distance must be a number > 0 (or empty for auto).");
    options.maxCorrespondenceDistance = d;
  }
  const seed = $("seed").value.trim();
  if (seed !== "") {
    const s = Number(seed);
    if (!Number.isSafeInteger(s) || s < 0) throw new Error("Seed must be a non-negative integer.");
    options.seed = s;
  }
  return options;
}

function clearResult() {
  state.result = null;
  showResult(null);
  view.setAligned(null);
  setView("before");
  updateButtons();
}

/** Cancels the running alignment (set while one runs). */
let cancelAlign = null;

async function align() {
  if (state.busy) return;
  clearError();
  clearResult();
  if (!state.source || !state.target) {
    showError("Load a source and a target scan first (or try the example).");
    return;
  }
  let options;
  try {
    options = readOptions();
  } catch (e) {
    showError(e.message);
    return;
  }
  // a keyboard user's focus, which leaves the button while it is disabled, comes back to it
  const focused = document.activeElement === $("align");
  state.busy = true;
  updateButtons();
  startProgress();
  const controller = new AbortController();
  cancelAlign = () => controller.abort();
  try {
    const arps = await getEngine();
    const truth = state.truth;
    // Copies made in the page's store ({ points, origin }), handed (transferred) to the engine's
    // worker: the main thread neither copies nor serialises the scans. The answer maps the
    // source's absolute frame (points + origin) onto the target's.
    const [source, target] = await Promise.all([copyCloud(state.source.key), copyCloud(state.target.key)]);
    controller.signal.throwIfAborted();
    const result = await arps.register(source, target, options, {
      onProgress: setStage,
      signal: controller.signal,
      transfer: true,
    });
    state.result = result;
    state.pose = 0;
    showResult(result, truth);
    view.setAligned(result.T_target_source);
    setView("after");
    view.fit(); // the target and the aligned source, which may reach beyond the view of before
    // One column (phones): bring the result into view.
    if (window.matchMedia("(max-width: 800px)").matches) $("results").scrollIntoView({ block: "start" });
  } catch (e) {
    if (e?.name === "AbortError") showError("Alignment cancelled.");
    else showError(`Alignment failed: ${e?.message ?? e}`);
  } finally {
    cancelAlign = null;
    state.busy = false;
    stopProgress();
    updateButtons();
    if (focused && (document.activeElement === document.body || document.activeElement === null)) $("align").focus();
  }
}

// (a value within 1e-12 of zero, the arithmetic's dust on an exact answer, is written 0)
const fmt = (x, digits = 4) => (Number.isFinite(x) ? (Math.abs(x) < 1e-12 ? "0" : Number(x.toPrecision(digits)).toString()) : String(x));

/** The index in `posesOf(r)` of the pose shown: 0 (the answer) unless the user picked another. */
function shownIndex(r = state.result) {
  return Math.min(state.pose, posesOf(r).length - 1);
}

/** The pose of the result shown (`posesOf`). */
function shownPose(r = state.result) {
  return posesOf(r)[shownIndex(r)];
}

function resultJson(r, truth) {
  const pose = shownPose(r);
  const m = pose.T_target_source;
  const out = {
    shown: pose.label,
    T_target_source: rowMajor(m),
    confidence: r.confidence,
    fitness: pose.fitness,
    inlierRmse: pose.inlierRmse,
    evidence: r.evidence,
    rotationDeg: rotationAngleDeg(m),
    translation: [m[12], m[13], m[14]],
    sourceCentreMoves: centreMoves(m, state.source),
    icpIterations: r.icpIterations,
    icpConverged: r.icpConverged,
    maxCorrespondenceDistance: r.maxCorrespondenceDistance,
    timings: r.timings,
    warnings: r.warnings,
    warningCodes: r.warningCodes,
    T_target_source_network: rowMajor(r.T_target_source_network),
    start: r.start,
    startsRefined: r.startsRefined,
    alternatives: (r.alternatives ?? []).map((a) => ({
      T_target_source: rowMajor(a.T_target_source),
      fitness: a.fitness,
      inlierRmse: a.inlierRmse,
    })),
  };
  if (truth) {
    const err = multiply(invertRigid(truth), m);
    out.exampleError = { rotationDeg: rotationAngleDeg(err), translation: Math.hypot(err[12], err[13], err[14]) };
  }
  return out;
}

function showResult(r, truth = null) {
  $("summary").hidden = !r;
  $("results-empty").hidden = !!r;
  if (!r) {
    $("result").textContent = "";
    $("alternatives").hidden = true;
    return;
  }
  const json = resultJson(r, truth);
  const pose = shownPose(r);
  showPoses(r);
  $("matrix").replaceChildren(
    ...json.T_target_source.map((row) => {
      const tr = document.createElement("tr");
      for (const v of row) {
        const td = document.createElement("td");
        td.textContent = (Math.abs(v) < 5e-5 ? 0 : v).toFixed(4); // never "-0.0000"
        tr.append(td);
      }
      return tr;
    }),
  );
  const t = json.timings;
  const verdict = confidenceWords(r.confidence, (r.alternatives ?? []).length);
  $("verdict").textContent = verdict.words;
  $("verdict").dataset.level = verdict.level;
  const d = fmt(r.maxCorrespondenceDistance, 3);
  // [term, figure, what it means in plain words]
  const rows = [
    ["Rotation", `${json.rotationDeg.toFixed(2)}°`, "How far the source turns to land on the target."],
    [
      "Translation",
      `(${json.translation.map((v) => fmt(v)).join(", ")}) · |t| = ${fmt(Math.hypot(...json.translation))} units`,
      "How far it then moves, in the scans' units.",
    ],
    // where the scans lie far from (0, 0, 0) (a map grid), the translation is that of a far point
    ...(json.sourceCentreMoves && farFromZero(state.source)
      ? [
          [
            "Centre moves",
            `(${json.sourceCentreMoves.map((v) => fmt(v)).join(", ")}) · ${fmt(Math.hypot(...json.sourceCentreMoves))} units`,
            "How far the source's centre moves. The translation above is that of the point (0, 0, 0), far from scans in map-grid coordinates.",
          ],
        ]
      : []),
    [
      "Fitness",
      `${(pose.fitness * 100).toFixed(1)}% of source points within ${d} units`,
      `The share of the moved source's points with a target point within ${d} units (the max correspondence distance). Partial overlap caps it below 100%.`,
    ],
    [
      "Inlier RMSE",
      `${fmt(pose.inlierRmse)} units`,
      `The typical (root mean square) distance between those matched points: the misfit left. Good alignments come near the scanner's noise, well under ${d}.`,
    ],
    [
      "ICP",
      `from the ${r.start} start (best of ${r.startsRefined} start${r.startsRefined === 1 ? "" : "s"} refined), ${r.icpIterations} iterations${r.icpIterations ? (r.icpConverged ? ", converged" : ", not converged") : ""}`,
    ],
    [
      "Time",
      `${t.totalMs.toFixed(0)} ms: prepare ${t.preprocessMs.toFixed(0)}, network ${t.networkMs.toFixed(0)}, GMR ${t.gmrMs.toFixed(0)}, ICP ${t.icpMs.toFixed(0)}${t.globalMs ? `, global ${t.globalMs.toFixed(0)}` : ""}`,
    ],
  ];
  if (json.exampleError) {
    rows.push([
      "vs. truth",
      `${json.exampleError.rotationDeg.toFixed(2)}° rotation error, ${fmt(json.exampleError.translation, 2)} translation error (example moved by 20°)`,
    ]);
  }
  $("figures").replaceChildren(
    ...rows.flatMap(([k, v, help]) => {
      const dt = document.createElement("dt");
      dt.textContent = k;
      const dd = document.createElement("dd");
      dd.textContent = v;
      if (help) {
        const small = document.createElement("small");
        small.className = "explain";
        small.textContent = help;
        dd.append(small);
      }
      return [dt, dd];
    }),
  );
  // the engine's warnings (less the API options the page does not offer), and where the page
  // can mend one: scans in different units
  const hints = r.warningCodes.includes("sizeMismatch")
    ? ["Different units? Say which under Units (with the scans): the source is then scaled into the target's unit."]
    : [];
  const warnings = r.warnings.map((w) => w.replace(/; `(outliers|supportPlane): "keep"` keeps (them|it)$/, ""));
  $("warnings").replaceChildren(
    ...[...warnings, ...hints].map((w) => {
      const li = document.createElement("li");
      li.textContent = w;
      return li;
    }),
  );
  $("result").textContent = JSON.stringify(json, null, 2);
}

/** True when `source`'s centre lies farther from (0, 0, 0) than ten times its size (a map grid). */
function farFromZero(source) {
  if (!source?.bounds) return false;
  const c = [0, 1, 2].map((k) => source.origin[k] + (source.bounds.min[k] + source.bounds.max[k]) / 2);
  const size = Math.max(...[0, 1, 2].map((k) => source.bounds.max[k] - source.bounds.min[k]));
  return Math.hypot(...c) > 10 * size;
}

/**
 * How far the column-major `m` moves the centre of `source`'s bounding box (in f64), `[x, y, z]`,
 * or null without a source. With map-grid coordinates the translation is the motion of the far
 * away point (0, 0, 0); this is the distance a user would measure on the scans.
 */
function centreMoves(m, source) {
  if (!source?.bounds) return null;
  const c = [0, 1, 2].map((k) => source.origin[k] + (source.bounds.min[k] + source.bounds.max[k]) / 2);
  return [0, 1, 2].map((r) => m[r] * c[0] + m[4 + r] * c[1] + m[8 + r] * c[2] + m[12 + r] - c[r]);
}

/** The buttons that pick the pose shown (#alternatives), when the result offers more than one. */
function showPoses(r) {
  const poses = posesOf(r);
  $("alternatives").hidden = poses.length < 2;
  $("alternatives-poses").replaceChildren(
    ...(poses.length < 2 ? [] : poses).map((p, k) => {
      const b = document.createElement("button");
      b.type = "button";
      b.textContent = `${k === 0 ? "Answer" : `Alternative ${k}`} · fitness ${(p.fitness * 100).toFixed(1)}%`;
      b.classList.toggle("on", k === shownIndex(r));
      b.setAttribute("aria-pressed", String(k === shownIndex(r)));
      b.addEventListener("click", () => showPose(k));
      return b;
    }),
  );
}

/** Shows pose `k` of the result (0 its answer, k its alternative k): view, matrix and figures. */
function showPose(k) {
  if (!state.result) return;
  state.pose = k;
  showResult(state.result, state.truth);
  view.setAligned(shownPose().T_target_source);
  setView("after");
}

async function copyMatrix() {
  if (!state.result) return;
  const text = JSON.stringify({ T_target_source: rowMajor(shownPose().T_target_source) });
  const button = $("copy-matrix");
  try {
    await navigator.clipboard.writeText(text);
  } catch {
    // Clipboard API unavailable (insecure context, permissions): the textarea fallback.
    const ta = document.createElement("textarea");
    ta.value = text;
    document.body.append(ta);
    ta.select();
    document.execCommand("copy");
    ta.remove();
  }
  button.textContent = "Copied ✓";
  setTimeout(() => (button.textContent = "Copy matrix as JSON"), 1500);
}

async function downloadAligned() {
  if (!state.result || !state.source) return;
  const { source, result } = state;
  const button = $("download-ply");
  button.disabled = true;
  try {
    // The package's own, in the engine's worker, every buffer transferred: the source's file moved
    // as it is, in its own format (its colours, intensity, normals and faces kept; the unit change
    // included; an E57 file by its scans' poses, one scan chosen as an E57 file of that scan),
    // else (a file without a known extension) the points from the page's store, moved (the origin
    // in f64) and written as PLY (doubles when the scan has one).
    const arps = await getEngine();
    const T = shownPose(result).T_target_source;
    let bytes = null;
    let ext = "ply";
    const own = source.file && /\.([a-z0-9]+)$/i.exec(source.file.name)?.[1].toLowerCase();
    const scan = source.scan ?? null;
    if (own) {
      // (a format transformFile does not move, or integer PLY coordinates, fall back to the points)
      const file = new Uint8Array(await source.file.arrayBuffer());
      const m = Array.from(T, (v, i) => (i < 12 && i % 4 < 3 ? v * source.scale : v)); // T S
      const options = scan === null ? null : { scan };
      bytes = await arps.transformFile(file, source.file.name, m, options, { transfer: true }).catch(() => null);
      if (bytes) ext = own;
    }
    if (!bytes) {
      const cloud = await copyCloud(source.key);
      bytes = await arps.writePly(await arps.transformPointCloud(cloud, T, { transfer: true }), { transfer: true });
    }
    const a = document.createElement("a");
    a.href = URL.createObjectURL(new Blob([bytes], { type: "application/octet-stream" }));
    const stem = (source.file?.name ?? source.name).replace(/\.[^.]*$/, "") + (scan === null ? "" : `-scan${scan + 1}`);
    a.download = `${stem.replace(/[^\w.-]+/g, "_").replace(/^_+|_+$/g, "") || "source"}-aligned.${ext}`;
    document.body.append(a);
    a.click();
    a.remove();
    setTimeout(() => URL.revokeObjectURL(a.href), 10_000);
  } catch (e) {
    showError(`Could not write the aligned source: ${e?.message ?? e}`);
  } finally {
    button.disabled = false;
  }
}

function setView(which) {
  state.view = which === "after" && state.result ? "after" : "before";
  for (const view of ["before", "after"]) {
    $(`view-${view}`).classList.toggle("on", state.view === view);
    $(`view-${view}`).setAttribute("aria-pressed", String(state.view === view));
  }
  $("legend-aligned").hidden = state.view !== "after";
  $("legend-source").hidden = state.view === "after";
  view.show(state.view);
}

// ---- wiring -------------------------------------------------------------------------------

const view = createView($("canvas"), { onError: (e) => showError(`The view failed: ${e.message}`) });

for (const which of ["source", "target"]) {
  const input = $(`${which}-file`);
  input.addEventListener("change", () => {
    loadFile(which, input.files[0]);
    input.value = ""; // picking the same file again fires "change" again
  });
  const zone = $(`${which}-drop`);
  zone.addEventListener("dragover", (e) => {
    e.preventDefault();
    zone.classList.add("over");
  });
  zone.addEventListener("dragleave", () => zone.classList.remove("over"));
  zone.addEventListener("drop", (e) => {
    e.preventDefault();
    zone.classList.remove("over");
    loadFile(which, e.dataTransfer.files[0]);
  });
}
// Files dropped on the view: two are source and target; one fills the empty slot (else the
// source). A drop anywhere else must not navigate away from the page.
window.addEventListener("dragover", (e) => e.preventDefault());
window.addEventListener("drop", (e) => e.preventDefault());
$("viewer").addEventListener("drop", (e) => {
  const files = [...e.dataTransfer.files];
  if (files.length >= 2) {
    loadFile("source", files[0]);
    loadFile("target", files[1]);
  } else if (files.length === 1) {
    loadFile(state.source && !state.target ? "target" : "source", files[0]);
  }
});

for (const id of ["source-unit", "target-unit"]) $(id).addEventListener("change", rescaleSource);
for (const which of ["source", "target"]) {
  $(`${which}-scan`).addEventListener("change", (e) => {
    const file = state[which]?.file;
    if (file) loadFile(which, file, e.target.value === "" ? null : Number(e.target.value));
  });
}
$("example").addEventListener("click", loadExample);
$("align").addEventListener("click", align);
$("cancel").addEventListener("click", () => cancelAlign?.());
$("copy-matrix").addEventListener("click", copyMatrix);
$("download-ply").addEventListener("click", downloadAligned);
$("view-before").addEventListener("click", () => setView("before"));
$("view-after").addEventListener("click", () => setView("after"));
$("point-size").addEventListener("input", (e) => view.setPointSize(Number(e.target.value)));
$("fit").addEventListener("click", () => view.fit());

updateButtons();
getEngine().catch((e) => showError(`The engine could not be loaded: ${e?.message ?? e}`));
