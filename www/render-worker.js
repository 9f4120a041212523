// The demo page's render worker: the three.js scene (www/scene.js) on the page canvas's
// OffscreenCanvas, so drawing (slow with software WebGL) never blocks the page. The first message
// is { type: "init", canvas }; every later one goes to the scene. After each frame it replies
// { type: "rendered", seq }.
import { createScene } from "./scene.js";

let handle = null;
self.addEventListener("message", ({ data }) => {
  try {
    if (data.type === "init") handle = createScene(data.canvas, (seq) => self.postMessage({ type: "rendered", seq }));
    else handle?.(data);
  } catch (e) {
    self.postMessage({ type: "error", message: e instanceof Error ? e.message : String(e) });
  }
});
