// ESM entry of the Node build: the same API as the web build (`await init()` then `Registrar`,
// `parsePointCloud`, `readPointCloud`, `version`). It re-exports the CommonJS entry (./arps.js: the facade over the
// glue that loads its .wasm synchronously from disk), so `init` and `initSync` just return.
import { createRequire } from "node:module";

const require = createRequire(import.meta.url);
const arps = require("./arps.js");

export const { Registrar, parsePointCloud, readPointCloud, version } = arps;

/** Nothing to do in Node (the module is ready on import); kept for parity with the web build. */
export default async function init() {
  return arps;
}

/** Nothing to do in Node; kept for parity with the web build. */
export function initSync() {
  return arps;
}
