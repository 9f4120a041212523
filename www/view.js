// The demo page's view, main-thread side: the camera and its OrbitControls, framing from bounding
// boxes (eight corners per cloud, never a pass over the points), and the scene (www/scene.js),
// which draws in a worker on an OffscreenCanvas where the browser can (render-worker.js), else
// here. Clouds arrive already subsampled (at most MAX_DRAWN points each; the engine gets them all),
// as float32 offsets from their own float64 origin. The scene's frame sits at the target's origin
// (else the source's): each cloud is placed there by the difference of origins, taken in f64, so
// two map-grid surveys are drawn, and framed, without rounding.
import * as THREE from "three";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";
import { relativeTo, transformBounds, unionBounds } from "./lib.js";
import { createScene } from "./scene.js";

/** At most this many points of each cloud are drawn (`?drawn=N` in the page's URL overrides it). */
export const MAX_DRAWN = Math.max(1000, Number(new URLSearchParams(location.search).get("drawn")) || 200_000);

/**
 * Sends messages to the scene: to its worker (`drawn` arrays are transferred), or to it here.
 * `onRendered(seq)` hears of each frame drawn.
 */
function sceneBackend(canvas, onError, onRendered) {
  if (typeof canvas.transferControlToOffscreen === "function" && typeof Worker === "function") {
    try {
      const offscreen = canvas.transferControlToOffscreen();
      const worker = new Worker(new URL("./render-worker.js", import.meta.url), { type: "module", name: "arps-page-render" });
      worker.addEventListener("message", ({ data }) => {
        if (data.type === "rendered") onRendered(data.seq);
        else if (data.type === "error") onError(new Error(data.message));
      });
      worker.addEventListener("error", (e) => {
        e.preventDefault();
        onError(new Error(`the view's worker failed: ${e.message || "unknown error"}`));
      });
      worker.postMessage({ type: "init", canvas: offscreen }, [offscreen]);
      return { send: (msg) => worker.postMessage(msg, msg.drawn ? [msg.drawn.buffer] : []), offscreen: true };
    } catch {
      /* no OffscreenCanvas WebGL here: draw on the page */
    }
  }
  const handle = createScene(canvas, onRendered);
  return { send: (msg) => handle(msg), offscreen: false };
}

/** `b` (`{ min, max }` or null) moved by `d`. */
const shifted = (b, d) => b && { min: b.min.map((v, k) => v + d[k]), max: b.max.map((v, k) => v + d[k]) };

/**
 * The view on `canvas`. Test hook: `canvas.dataset.sent` counts the changes sent to the scene,
 * `canvas.dataset.drawn` is the count the last drawn frame shows (equal: the view is up to date).
 * Methods: `setCloud(key, cloud)` (`key` "source" or "target", `cloud` `{ drawn, bounds, origin }`
 * or null: `drawn` and `bounds` offsets from `origin`, `[x, y, z]` or null for zero; `drawn` is
 * handed over, detached afterwards), `setAligned(T_target_source)` (column-major, between the
 * clouds' absolute frames, or null), `show("before" | "after")`, `setPointSize(px)`, `fit()`.
 * `offscreen` says where it draws.
 */
export function createView(canvas, { onError = (e) => console.error(e) } = {}) {
  let seq = 0;
  const backend = sceneBackend(canvas, onError, (drawn) => (canvas.dataset.drawn = drawn));
  const send = (msg) => {
    canvas.dataset.sent = ++seq;
    backend.send({ ...msg, seq });
  };
  const pixelRatio = Math.min(window.devicePixelRatio || 1, 2);
  const camera = new THREE.PerspectiveCamera(45, 1, 0.01, 1000);
  camera.position.set(3, 2, 4);
  // each cloud's bounds and origin as given; the scene's frame (an origin); the aligned pose
  const local = { source: null, target: null };
  const origins = { source: null, target: null };
  let frame = [0, 0, 0];
  let T_target_source = null;
  const visible = { source: true, aligned: false };
  const offset = (key) => origins[key].map((v, k) => v - frame[k]);
  const box = (key) => (local[key] ? shifted(local[key], offset(key)) : null);
  const alignedBox = () => (T_target_source && local.source ? transformBounds(local.source, alignedMatrix()) : null);
  // T_target_source acting on the source's offsets, giving scene coordinates
  const alignedMatrix = () => relativeTo(T_target_source, origins.source, frame);
  const sendAligned = () => send({ type: "aligned", matrix: T_target_source && local.source ? Array.from(alignedMatrix()) : null });
  /** Moves the scene's frame to the target's origin (else the source's) and re-places the clouds. */
  const reframe = () => {
    const next = origins.target ?? origins.source ?? [0, 0, 0];
    if (next.every((v, k) => v === frame[k])) return;
    frame = next;
    for (const key of ["source", "target"]) if (local[key]) send({ type: "offset", key, offset: offset(key) });
    if (T_target_source) sendAligned();
  };

  const sendCamera = () =>
    send({
      type: "camera",
      position: camera.position.toArray(),
      quaternion: camera.quaternion.toArray(),
      up: camera.up.toArray(),
      fov: camera.fov,
      near: camera.near,
      far: camera.far,
    });

  // OrbitControls keep the up axis they were made with: fit() makes new ones after turning it.
  let controls = null;
  const makeControls = () => {
    controls?.dispose();
    controls = new OrbitControls(camera, canvas);
    controls.addEventListener("change", sendCamera);
  };
  makeControls();

  new ResizeObserver(() => {
    const { clientWidth: w, clientHeight: h } = canvas;
    if (!w || !h) return;
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    send({ type: "resize", width: Math.round(w * pixelRatio), height: Math.round(h * pixelRatio) });
  }).observe(canvas);
  send({ type: "pointSize", px: 2 * pixelRatio });
  sendCamera();

  return {
    offscreen: backend.offscreen,
    setCloud(key, cloud) {
      if (key === "source") T_target_source = null;
      local[key] = cloud?.bounds ?? null;
      origins[key] = local[key] ? Array.from(cloud.origin ?? [0, 0, 0], Number) : null;
      reframe();
      const placed = local[key] ? { offset: offset(key) } : {};
      send({ type: "cloud", key, drawn: cloud?.drawn ?? null, bounds: local[key], ...placed });
    },
    setAligned(matrix) {
      T_target_source = matrix && local.source ? Float64Array.from(matrix) : null;
      sendAligned();
    },
    show(which) {
      visible.aligned = which === "after" && !!T_target_source;
      visible.source = !visible.aligned;
      send({ type: "visible", ...visible });
    },
    setPointSize(px) {
      send({ type: "pointSize", px: px * pixelRatio });
    },
    /** Frames the visible clouds' boxes; Z up when the data is flat in z (scans), else Y up (three.js). */
    fit() {
      const all = unionBounds([visible.source ? box("source") : null, box("target"), visible.aligned ? alignedBox() : null]);
      if (!all) return;
      const min = new THREE.Vector3(...all.min);
      const max = new THREE.Vector3(...all.max);
      const extent = max.clone().sub(min);
      const center = min.clone().add(max).multiplyScalar(0.5);
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
      sendCamera();
    },
  };
}
