// CommonJS entry of the Node build (pkg/node/arps.js): the facade (facade.cjs) over the raw
// wasm-bindgen glue (arps_glue.js, which loads arps_bg.wasm from disk on require). The same API
// as the web build; `init` and `initSync` are no-ops kept for parity (they return this module's
// public exports, never the raw glue, whose reset hook would break the facade).
"use strict";
const glue = require("./arps_glue.js");
const { makeApi } = require("./facade.cjs");

const api = makeApi(glue, () => true);
module.exports = {
  Registrar: api.Registrar,
  parsePointCloud: api.parsePointCloud,
  readPointCloud: api.readPointCloud,
  version: api.version,
  /** Nothing to do in Node (the module is ready on require); kept for parity with the web build. */
  default: async () => module.exports,
  /** Nothing to do in Node; kept for parity with the web build. */
  initSync: () => module.exports,
};
// Marks the default export as real, so that TypeScript's and bundlers' CommonJS interop
// (`esModuleInterop`'s __importDefault) gives `import init from "arps"` the function above.
Object.defineProperty(module.exports, "__esModule", { value: true });
