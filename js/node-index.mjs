// ESM entry of the Node build: the same API as the web build (`await init()` then `Registrar`,
// `parsePointCloud`, `readPointCloud`, `transformPointCloud`, `writePly`, `transformFile`, `canTransform`, `listScans`, `version`). It re-exports the CommonJS entry (./arps.js: the facade over the
// glue that loads its .wasm synchronously from disk on the first call), so `init` and `initSync` just return.
import { createRequire } from "node:module";

const require = createRequire(import.meta.url);
const arps = require("./arps.js");

export const { Registrar, parsePointCloud, readPointCloud, transformPointCloud, writePly, transformFile, canTransform, listScans, rigidFromPairs, version } =
  arps;

/** Nothing to do in Node (the engine loads on the first call); `init({ model })` sets another default model. */
export default async function init(options) {
  await arps.default(options);
  return arps;
}

/** Nothing to do in Node; `initSync({ model: bytes })` sets another default model. */
export function initSync(options) {
  arps.initSync(options);
  return arps;
}
