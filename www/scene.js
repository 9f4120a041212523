// The demo page's three.js scene and renderer, driven by messages (so it can live in a worker on
// an OffscreenCanvas, www/render-worker.js, or on the page when there is none). It draws what it
// is given (each cloud's subsample), never walks the points itself (culling spheres come from the
// bounds it is sent), and renders once per animation frame after a change.
//   { type: "cloud", key: "source" | "target", drawn?: Float32Array, bounds?, offset? }   set or
//       clear; `offset` [x, y, z] places the cloud in the scene (drawn + offset)
//   { type: "offset", key, offset }              moves a cloud to a new place
//   { type: "aligned", matrix?: number[16] }     the source's drawn points under this matrix (to
//       scene coordinates), or none
//   { type: "visible", source: bool, aligned: bool }
//   { type: "pointSize", px }
//   { type: "camera", position, quaternion, up, fov, near, far }
//   { type: "resize", width, height }             device pixels
// Each message may carry a sequence number `seq`; after a frame is drawn, `onRendered(seq)` gets
// that of the last message it shows.
// A URL, not the bare "three": workers do not see the page's import map. It resolves to the same
// module the map gives the page, so the page and this file share one three.js.
import * as THREE from "../node_modules/three/build/three.module.js";

const COLORS = { source: 0xf97316, target: 0x38bdf8, aligned: 0x4ade80 };

const nextFrame = typeof requestAnimationFrame === "function" ? requestAnimationFrame : (f) => setTimeout(f, 16);

/**
 * A renderer on `canvas` (an HTMLCanvasElement or OffscreenCanvas); returns its message handler.
 * `onRendered(seq)` is called after each frame.
 */
export function createScene(canvas, onRendered = () => {}) {
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: true });
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0x0f172a);
  const camera = new THREE.PerspectiveCamera(45, 1, 0.01, 1000);
  const objects = { source: null, target: null, aligned: null };
  let px = 2;
  let pending = false;
  let size = [0, 0];
  let seq = 0;

  const render = () => {
    pending = false;
    if (size[0] && size[1]) renderer.render(scene, camera);
    onRendered(seq);
  };
  const requestRender = () => {
    if (!pending) {
      pending = true;
      nextFrame(render);
    }
  };
  const material = (color) => new THREE.PointsMaterial({ color, size: px, sizeAttenuation: false });
  const remove = (key) => {
    const o = objects[key];
    if (!o) return;
    scene.remove(o);
    if (key !== "aligned") o.geometry.dispose(); // aligned shares the source's
    o.material.dispose();
    objects[key] = null;
  };

  return function handle(msg) {
    if (Number.isFinite(msg.seq)) seq = msg.seq;
    switch (msg.type) {
      case "cloud": {
        if (msg.key === "source") remove("aligned");
        remove(msg.key);
        if (msg.drawn && msg.bounds) {
          const geometry = new THREE.BufferGeometry();
          geometry.setAttribute("position", new THREE.BufferAttribute(msg.drawn, 3));
          const min = new THREE.Vector3(...msg.bounds.min);
          const max = new THREE.Vector3(...msg.bounds.max);
          geometry.boundingSphere = new THREE.Sphere(min.clone().add(max).multiplyScalar(0.5), min.distanceTo(max) / 2);
          objects[msg.key] = new THREE.Points(geometry, material(COLORS[msg.key]));
          if (msg.offset) objects[msg.key].position.fromArray(msg.offset);
          scene.add(objects[msg.key]);
        }
        break;
      }
      case "offset":
        objects[msg.key]?.position.fromArray(msg.offset);
        break;
      case "aligned": {
        remove("aligned");
        if (msg.matrix && objects.source) {
          const aligned = new THREE.Points(objects.source.geometry, material(COLORS.aligned));
          aligned.matrixAutoUpdate = false;
          aligned.matrix.fromArray(msg.matrix);
          aligned.matrixWorldNeedsUpdate = true;
          objects.aligned = aligned;
          scene.add(aligned);
        }
        break;
      }
      case "visible":
        if (objects.source) objects.source.visible = msg.source;
        if (objects.aligned) objects.aligned.visible = msg.aligned;
        break;
      case "pointSize":
        px = msg.px;
        for (const o of Object.values(objects)) if (o) o.material.size = px;
        break;
      case "camera":
        camera.position.fromArray(msg.position);
        camera.quaternion.fromArray(msg.quaternion);
        camera.up.fromArray(msg.up);
        camera.fov = msg.fov;
        camera.near = msg.near;
        camera.far = msg.far;
        camera.updateProjectionMatrix();
        break;
      case "resize":
        size = [msg.width, msg.height];
        renderer.setSize(msg.width, msg.height, false);
        camera.aspect = msg.width / msg.height;
        camera.updateProjectionMatrix();
        break;
      default:
        throw new Error(`scene: unknown message ${JSON.stringify(msg.type)}`);
    }
    requestRender();
  };
}
