// CommonJS entry of the Node build (pkg/node/arps.js): the facade (facade.cjs) over the raw
// wasm-bindgen glue (arps_glue.js, which loads ../arps_bg.wasm, the web build's, from disk when
// it is required). The glue is required on the first call, not on import: a server-side bundle
// (Next.js, webpack `target: "node"`) that includes the package but never calls it on the server
// imports it without the .wasm beside it. The same API as the web build. The default model is
// ../models/arps-web.safetensors, read from disk when `Registrar.withDefaultModel()` first needs
// it; `Registrar.fromUrl` reads `file:` URLs from disk and fetches the others. `init` and
// `initSync` need not be called; they take the same options as the web build's (`{ model }` sets
// another default model).
// `init`/`initSync` return this module's public exports, never the raw glue (whose reset hook
// would break the facade).
"use strict";
const fs = require("node:fs");
const path = require("node:path");
const { fileURLToPath } = require("node:url");
const { makeApi, modelBytes } = require("./facade.cjs");

const WASM = path.join(__dirname, "..", "arps_bg.wasm");
/** What to do about a file a server bundle left behind (the .wasm, the default model). */
const LEFT_BEHIND =
  "a bundler that copied the package's JavaScript into a server bundle left it behind: " +
  'keep the package out of the server bundle (Next.js `serverExternalPackages: ["arps"]`, ' +
  "webpack `externals`), or import it only in client code";
let loaded;
/** The glue, required on first use; a .wasm that is not where the glue looks is a clear error. */
function loadGlue() {
  if (loaded === undefined) {
    try {
      loaded = require("./arps_glue.js");
    } catch (e) {
      if (e?.code !== "ENOENT") throw e;
      throw new Error(`arps: its WebAssembly file is not at ${WASM} (${e.message}): ${LEFT_BEHIND}`, { cause: e });
    }
  }
  return loaded;
}
const glue = new Proxy({}, { get: (_, key) => loadGlue()[key] });

/** The default model's bytes; a file that is not where it should be is a clear error (as the .wasm). */
function readDefaultModel() {
  try {
    return fs.readFileSync(DEFAULT_MODEL);
  } catch (e) {
    if (e?.code !== "ENOENT") throw e;
    throw new Error(`the default model is not at ${DEFAULT_MODEL}: ${LEFT_BEHIND}`, { cause: e });
  }
}

const DEFAULT_MODEL = path.join(__dirname, "..", "models", "arps-web.safetensors");

/** `file:` URLs (and plain paths that are not URLs) are read from disk; `undefined`: fetch it. */
async function readUrl(url, signal) {
  let file;
  try {
    const u = new URL(url);
    if (u.protocol !== "file:") return undefined;
    file = fileURLToPath(u);
  } catch {
    file = url; // not a URL: a path
  }
  try {
    return await fs.promises.readFile(file, signal ? { signal } : undefined);
  } catch (e) {
    if (e?.name === "AbortError") throw e;
    throw new Error(`arps: reading the model ${url} failed: ${e.message}`, { cause: e });
  }
}

const api = makeApi(glue, () => true, {
  readDefaultModel,
  readUrl,
});

const modelOption = (options) =>
  options !== null && typeof options === "object" && Object.getPrototypeOf(options) === Object.prototype ? options.model : undefined;

module.exports = {
  Registrar: api.Registrar,
  parsePointCloud: api.parsePointCloud,
  readPointCloud: api.readPointCloud,
  transformPointCloud: api.transformPointCloud,
  writePly: api.writePly,
  transformFile: api.transformFile,
  canTransform: api.canTransform,
  listScans: api.listScans,
  rigidFromPairs: api.rigidFromPairs,
  version: api.version,
  /**
   * Nothing to do in Node (the engine loads on the first call; the default model is read from
   * disk on first use); `init({ model })` with a URL, path or bytes sets another default model.
   */
  default: async (options) => {
    const model = modelOption(options);
    if (model !== undefined && model !== null && typeof model !== "boolean") {
      api.setDefaultModel(await modelBytes(model, undefined, readUrl), "the model given to init()");
    }
    return module.exports;
  },
  /** Nothing to do in Node; `initSync({ model: bytes })` sets another default model. */
  initSync: (options) => {
    const model = modelOption(options);
    if (model !== undefined && model !== null && typeof model !== "boolean") api.setDefaultModel(model, "the model given to initSync()");
    return module.exports;
  },
};
// Marks the default export as real, so that TypeScript's and bundlers' CommonJS interop
// (`esModuleInterop`'s __importDefault) gives `import init from "arps"` the function above.
Object.defineProperty(module.exports, "__esModule", { value: true });
