// The arps demo page: load two scans (parsed in wasm), align them in the worker, show the result
// in three.js. Test hooks: #source-file, #target-file, #align, #result (the result as JSON),
// #verdict (the confidence in words), #error (the message).
import * as THREE from "three";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";
import { createWorkerRegistrar, STAGES } from "../pkg/worker-client.js";
import {
  confidenceWords,
  finitePoints,
  makeExample,
  multiply,
  invertRigid,
  parseBunny,
  rotationAngleDeg,
  rowMajor,
  transformPoints,
  writePly,
} from "./lib.js";

const $ = (id) => document.getElementById(id);
const COLORS = { source: 0xf97316, target: 0x38bdf8, aligned: 0x4ade80 };

// ---- state --------------------------------------------------------------------------------

const state = {
  source: null, // { points: Float32Array, name }
  target: null,
  truth: null, // the example's known T_target_source (column-major), if the example is loaded
  result: null, // the last RegistrationResult
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
        const untrained = arps.provenance?.kind === "random";
        setBadge(
          `engine ready · ${untrained ? "untrained placeholder model" : `model “${arps.modelConfig?.preset ?? "?"}”`}`,
          untrained ? "warn" : "ok",
          untrained
            ? "The embedded network weights are an untrained placeholder: ICP does the work until trained weights ship."
            : `Model preset ${arps.modelConfig?.preset}, N = ${arps.modelConfig?.nPoints}; provenance ${JSON.stringify(arps.provenance)}`,
        );
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

function setBadge(text, kind, title = "") {
  const b = $("engine-status");
  b.textContent = text;
  b.className = `badge ${kind}`;
  b.title = title;
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
  $("align").disabled = state.busy || !state.source || !state.target;
  $("example").disabled = state.busy;
  $("source-file").disabled = state.busy;
  $("target-file").disabled = state.busy;
  $("view-after").disabled = !state.result;
}

// ---- loading scans ------------------------------------------------------------------------

const loads = { source: 0, target: 0 }; // the latest load of each slot wins

async function loadFile(which, file) {
  if (!file || state.busy) return;
  const token = ++loads[which];
  clearError();
  setCloud(which, null);
  $(`${which}-info`).textContent = `reading ${file.name}…`;
  try {
    const bytes = new Uint8Array(await file.arrayBuffer());
    const arps = await getEngine();
    const parsed = await arps.parsePointCloud(bytes, file.name, { transfer: true });
    if (token !== loads[which]) return;
    const { points, dropped } = finitePoints(parsed);
    if (points.length === 0) throw new Error("the file holds no (finite) points");
    setCloud(which, { points, name: file.name, note: dropped ? `${dropped} non-finite dropped` : "" });
  } catch (e) {
    if (token !== loads[which]) return;
    setCloud(which, null);
    showError(`Could not read ${file.name}: ${e?.message ?? e}`);
  }
}

function setCloud(which, cloud) {
  state[which] = cloud;
  state.result = null;
  state.truth = null;
  const info = $(`${which}-info`);
  info.textContent = cloud
    ? `${cloud.name} · ${(cloud.points.length / 3).toLocaleString("en")} points${cloud.note ? ` · ${cloud.note}` : ""}`
    : "drop a file or click to choose";
  $(`${which}-drop`).classList.toggle("loaded", !!cloud);
  showResult(null);
  view.setClouds(state.source?.points ?? null, state.target?.points ?? null);
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
    loads.source++;
    loads.target++;
    setCloud("source", { points: example.source, name: "bunny, view A (moved)" });
    setCloud("target", { points: example.target, name: "bunny, view B" });
    state.truth = example.truth;
  } catch (e) {
    showError(`Could not make the example: ${e?.message ?? e}`);
  }
}

// ---- aligning -----------------------------------------------------------------------------

function readOptions() {
  const options = { icp: $("icp").value, search: $("search").value };
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
  state.busy = true;
  updateButtons();
  startProgress();
  const controller = new AbortController();
  cancelAlign = () => controller.abort();
  try {
    const arps = await getEngine();
    const truth = state.truth;
    const result = await arps.register(state.source.points, state.target.points, options, {
      onProgress: setStage,
      signal: controller.signal,
    });
    state.result = result;
    showResult(result, truth);
    view.setAligned(result.T_target_source);
    setView("after");
  } catch (e) {
    if (e?.name === "AbortError") showError("Alignment cancelled.");
    else showError(`Alignment failed: ${e?.message ?? e}`);
  } finally {
    cancelAlign = null;
    state.busy = false;
    stopProgress();
    updateButtons();
  }
}

const fmt = (x, digits = 4) => (Number.isFinite(x) ? Number(x.toPrecision(digits)).toString() : String(x));

function resultJson(r, truth) {
  const m = r.T_target_source;
  const out = {
    T_target_source: rowMajor(m),
    confidence: r.confidence,
    fitness: r.fitness,
    inlierRmse: r.inlierRmse,
    evidence: r.evidence,
    rotationDeg: rotationAngleDeg(m),
    translation: [m[12], m[13], m[14]],
    icpIterations: r.icpIterations,
    icpConverged: r.icpConverged,
    maxCorrespondenceDistance: r.maxCorrespondenceDistance,
    timings: r.timings,
    warnings: r.warnings,
    T_target_source_network: rowMajor(r.T_target_source_network),
    start: r.start,
    startsRefined: r.startsRefined,
  };
  if (truth) {
    const err = multiply(invertRigid(truth), m);
    out.exampleError = { rotationDeg: rotationAngleDeg(err), translation: Math.hypot(err[12], err[13], err[14]) };
  }
  return out;
}

function showResult(r, truth = null) {
  $("summary").hidden = !r;
  if (!r) {
    $("result").textContent = "";
    return;
  }
  const json = resultJson(r, truth);
  $("matrix").replaceChildren(
    ...json.T_target_source.map((row) => {
      const tr = document.createElement("tr");
      for (const v of row) {
        const td = document.createElement("td");
        td.textContent = v.toFixed(4);
        tr.append(td);
      }
      return tr;
    }),
  );
  const t = json.timings;
  const verdict = confidenceWords(r.confidence);
  $("verdict").textContent = verdict.words;
  $("verdict").dataset.level = verdict.level;
  const rows = [
    ["Rotation", `${json.rotationDeg.toFixed(2)}°`],
    ["Translation", `(${json.translation.map((v) => fmt(v)).join(", ")}) · |t| = ${fmt(Math.hypot(...json.translation))}`],
    ["Fitness", `${(r.fitness * 100).toFixed(1)}% of source points within ${fmt(r.maxCorrespondenceDistance, 3)}`],
    ["Inlier RMSE", fmt(r.inlierRmse)],
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
    ...rows.flatMap(([k, v]) => {
      const dt = document.createElement("dt");
      dt.textContent = k;
      const dd = document.createElement("dd");
      dd.textContent = v;
      return [dt, dd];
    }),
  );
  $("warnings").replaceChildren(
    ...r.warnings.map((w) => {
      const li = document.createElement("li");
      li.textContent = w;
      return li;
    }),
  );
  $("result").textContent = JSON.stringify(json, null, 2);
}

async function copyMatrix() {
  if (!state.result) return;
  const text = JSON.stringify({ T_target_source: rowMajor(state.result.T_target_source) });
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

function downloadAligned() {
  if (!state.result || !state.source) return;
  const aligned = transformPoints(state.source.points, state.result.T_target_source);
  const bytes = writePly(aligned, `arps: ${state.source.name} aligned onto ${state.target.name}`);
  const a = document.createElement("a");
  a.href = URL.createObjectURL(new Blob([bytes], { type: "application/octet-stream" }));
  a.download = `${state.source.name.replace(/\.[^.]*$/, "").replace(/[^\w.-]+/g, "_") || "source"}-aligned.ply`;
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 10_000);
}

// ---- the three.js view --------------------------------------------------------------------

function createView(canvas) {
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0x0f172a);
  const camera = new THREE.PerspectiveCamera(45, 1, 0.01, 1000);
  camera.position.set(3, 2, 4);
  let controls = null;
  const objects = { source: null, target: null, aligned: null };
  let size = 2;
  let pending = false;

  const render = () => {
    pending = false;
    renderer.render(scene, camera);
  };
  const requestRender = () => {
    if (!pending) {
      pending = true;
      requestAnimationFrame(render);
    }
  };

  const makeControls = () => {
    controls?.dispose();
    controls = new OrbitControls(camera, canvas);
    controls.addEventListener("change", requestRender);
  };
  makeControls();

  const material = (color) =>
    new THREE.PointsMaterial({ color, size: size * renderer.getPixelRatio(), sizeAttenuation: false });

  const replace = (key, points, color) => {
    if (objects[key]) {
      scene.remove(objects[key]);
      if (key !== "aligned") objects[key].geometry.dispose(); // aligned shares the source's
      objects[key].material.dispose();
      objects[key] = null;
    }
    if (!points) return;
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute("position", new THREE.BufferAttribute(points, 3));
    geometry.computeBoundingSphere();
    objects[key] = new THREE.Points(geometry, material(color));
    scene.add(objects[key]);
  };

  new ResizeObserver(() => {
    const { clientWidth: w, clientHeight: h } = canvas;
    if (!w || !h) return;
    renderer.setSize(w, h, false);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    render();
  }).observe(canvas);

  return {
    setClouds(source, target) {
      replace("aligned", null);
      replace("source", source ? source.slice() : null, COLORS.source);
      replace("target", target ? target.slice() : null, COLORS.target);
      $("empty").hidden = !!(source || target);
      requestRender();
    },
    setAligned(matrix) {
      replace("aligned", null);
      requestRender();
      if (!objects.source || !matrix) return;
      const aligned = new THREE.Points(objects.source.geometry, material(COLORS.aligned));
      aligned.matrixAutoUpdate = false;
      aligned.matrix.fromArray(matrix);
      aligned.matrixWorldNeedsUpdate = true;
      objects.aligned = aligned;
      scene.add(aligned);
      requestRender();
    },
    show(which) {
      if (objects.source) objects.source.visible = which === "before" || !objects.aligned;
      if (objects.aligned) objects.aligned.visible = which === "after";
      requestRender();
    },
    setPointSize(px) {
      size = px;
      for (const o of Object.values(objects)) if (o) o.material.size = size * renderer.getPixelRatio();
      requestRender();
    },
    /** Frames every cloud; Z up when the data is flat in z (scans), else Y up (three.js). */
    fit() {
      const box = new THREE.Box3();
      for (const o of Object.values(objects)) if (o) box.expandByObject(o);
      if (box.isEmpty()) return requestRender();
      const extent = box.getSize(new THREE.Vector3());
      const center = box.getCenter(new THREE.Vector3());
      const radius = Math.max(extent.length() / 2, 1e-6);
      const zUp = extent.z < 0.5 * Math.min(extent.x, extent.y);
      camera.up.set(0, zUp ? 0 : 1, zUp ? 1 : 0);
      const dir = zUp ? new THREE.Vector3(-0.6, -1, 0.8) : new THREE.Vector3(0.5, 0.45, 1);
      const dist = radius / Math.sin(THREE.MathUtils.degToRad(camera.fov / 2)) / Math.min(1, camera.aspect || 1);
      camera.position.copy(center).addScaledVector(dir.normalize(), dist * 0.9);
      camera.near = dist / 1000;
      camera.far = dist * 10;
      camera.updateProjectionMatrix();
      makeControls();
      controls.target.copy(center);
      controls.update();
      requestRender();
    },
  };
}

function setView(which) {
  state.view = which === "after" && state.result ? "after" : "before";
  $("view-before").classList.toggle("on", state.view === "before");
  $("view-after").classList.toggle("on", state.view === "after");
  $("legend-aligned").hidden = state.view !== "after";
  $("legend-source").hidden = state.view === "after";
  view.show(state.view);
}

// ---- wiring -------------------------------------------------------------------------------

const view = createView($("canvas"));

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
