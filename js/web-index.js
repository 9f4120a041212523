// The package's web entry (pkg/arps.js): `await init()` (instantiates arps_bg.wasm and fetches the
// default model, models/arps-web.safetensors, in parallel; both next to this file by default) or
// `initSync()`, then `Registrar`, `parsePointCloud`, `readPointCloud`, `transformPointCloud`,
// `writePly`, `transformFile`, `canTransform`, `listScans`, `version`. The API is the
// facade's (facade.js) over the raw wasm-bindgen glue (arps_glue.js): inputs checked at the
// boundary, and a trap re-instantiates the module instead of leaving it broken.
import glueInit, * as glue from "./arps_glue.js";
import { makeApi, modelBytes } from "./facade.js";

let ready = false;

const api = makeApi(glue, () => ready);

/** `{ module_or_path, model }` from init's argument (or the deprecated bare module/path). */
function initArgs(options) {
  const plain = options !== null && typeof options === "object" && Object.getPrototypeOf(options) === Object.prototype;
  if (!plain) return { moduleOrPath: options, model: true };
  const { module_or_path: moduleOrPath, model = true } = options;
  return { moduleOrPath, model };
}

/**
 * Loads and instantiates the engine and, in parallel, the default model. Call once, first.
 * `options.module_or_path`: the engine (a URL, `Response`, bytes or `WebAssembly.Module`;
 * default `arps_bg.wasm` next to this file). `options.model`: the default model that
 * `Registrar.withDefaultModel()` uses (`true`, the default: `models/arps-web.safetensors` next to
 * this file; a URL, `Request`, `Response` or bytes; `false`: none, e.g. when only
 * `Registrar.fromBytes`/`fromUrl` are used). Rejects with an `Error` naming the URL and the HTTP
 * status when the model cannot be fetched, or saying that the file is not an arps weights file.
 */
export default async function init(options) {
  const { moduleOrPath, model } = initArgs(options);
  const engine = glueInit(moduleOrPath === undefined ? undefined : { module_or_path: moduleOrPath }).then(
    (exports) => {
      ready = true;
      return exports;
    },
    (e) => {
      // a server that has no file at the engine's URL often answers with a page (200, HTML)
      // (V8 and SpiderMonkey say "magic word"/"magic number", JavaScriptCore "doesn't start with '\0asm'")
      if (e instanceof WebAssembly.CompileError && /magic|\\0asm|start with/i.test(e.message)) {
        const which =
          moduleOrPath === undefined
            ? "arps_bg.wasm (next to the package's arps.js)"
            : typeof moduleOrPath === "string" || moduleOrPath instanceof URL
              ? String(moduleOrPath)
              : (moduleOrPath instanceof Response && moduleOrPath.url) || "given to init()";
        const bytes = moduleOrPath !== undefined && (moduleOrPath instanceof ArrayBuffer || ArrayBuffer.isView(moduleOrPath));
        if (bytes) {
          throw new Error(
            `arps: the engine's bytes given to init() are not WebAssembly (${e.message}): pass the contents of the package's arps_bg.wasm`,
            { cause: e },
          );
        }
        throw new Error(
          `arps: the engine ${which} is not WebAssembly (${e.message}): the server answered with something else, ` +
            "often a page for a path it does not have. Under Vite's dev server, exclude the package from " +
            'dependency pre-bundling (vite.config: optimizeDeps: { exclude: ["arps"] }); otherwise pass the URL ' +
            "arps_bg.wasm is served at as init({ module_or_path })",
          { cause: e },
        );
      }
      // Node's fetch cannot read file: URLs ("fetch failed"): the web build run under Node
      const where = moduleOrPath === undefined ? new URL("./arps_bg.wasm", import.meta.url) : moduleOrPath;
      if (e instanceof TypeError && String(where).startsWith("file:")) {
        throw new Error(
          `arps: cannot fetch the engine ${where} (${e.message}${e.cause?.message ? `: ${e.cause.message}` : ""}): ` +
            "this is the package's web build, which fetches its files, and this runtime's fetch cannot read file: URLs. " +
            'Under Node import "arps" (its exports give Node the Node build, which reads them from disk), ' +
            "or pass the engine's bytes: init({ module_or_path: bytes })",
          { cause: e },
        );
      }
      throw e;
    },
  );
  let bytes = null;
  let what = "the model given to init()";
  if (model === true) {
    // A literal `new URL("./…", import.meta.url)`: bundlers (Vite, webpack) emit the file as an asset.
    const url = new URL("./models/arps-web.safetensors", import.meta.url);
    what = `the default model ${url}`;
    bytes = modelBytes(url).catch((e) => {
      throw new Error(`${e.message} (init({ model: false }) skips the default model; init({ model: url }) loads it from elsewhere)`, { cause: e });
    });
  } else if (model !== false && model !== null) {
    bytes = modelBytes(model);
  }
  // both settled before either error is thrown: a model that cannot be fetched rejects only once
  // the engine is loaded, so that a caller's fallback (Registrar.fromBytes, say) can use it at once
  const [loaded, fetched] = await Promise.allSettled([engine, bytes]);
  if (loaded.status === "rejected") throw loaded.reason;
  if (fetched.status === "rejected") throw fetched.reason;
  if (fetched.value) api.setDefaultModel(fetched.value, what);
  return loaded.value;
}

/**
 * `init` from bytes or a compiled module, synchronously: `initSync({ module, model? })`, `model`
 * the default model's bytes (nothing is fetched: without `model`, `withDefaultModel()` throws).
 */
export function initSync(options) {
  const plain = options !== null && typeof options === "object" && Object.getPrototypeOf(options) === Object.prototype;
  const exports = glue.initSync(plain ? { module: options.module } : options);
  ready = true;
  if (plain && options.model !== undefined && options.model !== null) api.setDefaultModel(options.model, "the model given to initSync()");
  return exports;
}

export const { Registrar, parsePointCloud, readPointCloud, transformPointCloud, writePly, transformFile, canTransform, listScans, rigidFromPairs, version } = api;
