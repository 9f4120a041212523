// The package's web entry (pkg/arps.js): `await init()` (fetches arps_bg.wasm) or `initSync()`,
// then `Registrar`, `parsePointCloud`, `readPointCloud`, `version`. The API is the facade's
// (facade.js) over the raw wasm-bindgen glue (arps_glue.js): inputs checked at the boundary, and
// a trap re-instantiates the module instead of leaving it broken.
import glueInit, * as glue from "./arps_glue.js";
import { makeApi } from "./facade.js";

let ready = false;

/**
 * Loads and instantiates the engine (`arps_bg.wasm` next to this file by default; or
 * `{ module_or_path }`: a URL, `Response`, bytes or `WebAssembly.Module`). Call once, first.
 */
export default async function init(moduleOrPath) {
  const exports = await glueInit(moduleOrPath);
  ready = true;
  return exports;
}

/** `init` from bytes or a compiled module, synchronously: `initSync({ module })`. */
export function initSync(module) {
  const exports = glue.initSync(module);
  ready = true;
  return exports;
}

export const { Registrar, parsePointCloud, readPointCloud, version } = makeApi(glue, () => ready);
