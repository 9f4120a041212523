// arps worker: runs the engine off the main thread. A module worker; start it with
// `createWorkerRegistrar()` from `arps/worker-client` (or `new Worker(new URL("./worker.js",
// import.meta.url), { type: "module" })` and the message protocol below).
//
// Requests (main -> worker), each with a numeric `id`:
//   { id, type: "init", wasm?, model?, weights? }   load the engine and the model (once): `model`
//                                           the default model (init's option), `weights` a custom
//                                           one instead (bytes, or a URL string: fetched)
//   { id, type: "register", source, target, options? }
//   { id, type: "parse", bytes, fileName, options? }
//   { id, type: "read", bytes, fileName, options? }   readPointCloud: { points, origin }
//   { id, type: "transform", cloud, matrix }   transformPointCloud: { points, origin }
//   { id, type: "write", cloud }            writePly: the PLY file's bytes
//   { id, type: "move", bytes, fileName, matrix, options }  transformFile: the moved file's bytes
//   { id, type: "scans", bytes, fileName }  listScans: an E57 file's scans
//   { id, type: "forget" }                  forgetTarget: the kept target's memory given back
// Replies (worker -> main), with the request's `id`:
//   { id, type: "progress", stage }         stage: "loading" | "preparing" | "network" | "refining" | "done"
//   { id, type: "ready", provenance, modelConfig }
//   { id, type: "result", result }          the result, copied (plain arrays: small)
//   { id, type: "parsed", points }          points (Float32Array) buffer transferred
//   { id, type: "read", cloud }             cloud.points buffer transferred (read and transform)
//   { id, type: "written", bytes }          bytes (Uint8Array) buffer transferred
//   { id, type: "scans", scans }            ScanInfo[]
//   { id, type: "forgotten" }               the kept target dropped (nothing loaded: nothing to drop)
//   { id, type: "error", message, name, code? }   code: "ARPS_TRAPPED" | "ARPS_UNUSABLE" after a trap
import init, { listScans, Registrar, parsePointCloud, readPointCloud, transformFile, transformPointCloud, writePly } from "./arps.js";

let registrar = null;
let loading = null;

const post = (message, transfer = []) => self.postMessage(message, transfer);
const progress = (id, stage) => post({ id, type: "progress", stage });

function load(id, { wasm, model, weights } = {}) {
  if (registrar) return Promise.resolve(registrar);
  if (!loading) {
    progress(id, "loading");
    loading = (async () => {
      const custom = weights !== undefined && weights !== null;
      // The default model is fetched in parallel with the engine, unless custom weights replace it.
      await init({ module_or_path: wasm ?? undefined, model: custom ? false : (model ?? true) });
      if (!custom) registrar = Registrar.withDefaultModel();
      else if (typeof weights === "string") registrar = await Registrar.fromUrl(weights);
      else registrar = Registrar.fromBytes(weights);
      return registrar;
    })();
    // A failed load may be retried by a later request (e.g. with other `wasm`/`weights`).
    loading.catch(() => {
      loading = null;
    });
  }
  return loading;
}

async function handle(msg) {
  const { id, type } = msg;
  switch (type) {
    case "init": {
      const r = await load(id, msg);
      post({ id, type: "ready", provenance: r.provenance, modelConfig: r.modelConfig });
      return;
    }
    case "register": {
      const r = await load(id);
      progress(id, "preparing");
      // "preparing" was just sent; the engine reports "network" and "refining" as they start.
      const result = r.register(msg.source, msg.target, msg.options ?? undefined, (stage) => {
        if (stage !== "preparing") progress(id, stage);
      });
      progress(id, "done");
      post({ id, type: "result", result }, []);
      return;
    }
    case "parse": {
      await load(id);
      const points = parsePointCloud(msg.bytes, msg.fileName, msg.options ?? undefined);
      post({ id, type: "parsed", points }, [points.buffer]);
      return;
    }
    case "read": {
      await load(id);
      const cloud = readPointCloud(msg.bytes, msg.fileName, msg.options ?? undefined);
      post({ id, type: "read", cloud }, [cloud.points.buffer]);
      return;
    }
    case "transform": {
      await load(id);
      const cloud = transformPointCloud(msg.cloud, msg.matrix);
      post({ id, type: "read", cloud }, [cloud.points.buffer]);
      return;
    }
    case "write": {
      await load(id);
      const bytes = writePly(msg.cloud);
      post({ id, type: "written", bytes }, [bytes.buffer]);
      return;
    }
    case "scans": {
      await load(id);
      post({ id, type: "scans", scans: listScans(msg.bytes, msg.fileName) });
      return;
    }
    case "move": {
      await load(id);
      const bytes = transformFile(msg.bytes, msg.fileName, msg.matrix, msg.options);
      post({ id, type: "written", bytes }, [bytes.buffer]);
      return;
    }
    case "forget": {
      // a worker that has not loaded holds no target: nothing to load for it
      if (registrar) registrar.forgetTarget();
      post({ id, type: "forgotten" });
      return;
    }
    default:
      throw new Error(`arps worker: unknown request type ${JSON.stringify(type)}`);
  }
}

// a request whose data could not be received here: the client fails the request in flight
self.addEventListener("messageerror", () => {
  post({ type: "undeliverable", message: "its data could not be deserialized in the worker" });
});
self.addEventListener("message", (event) => {
  const msg = event.data ?? {};
  handle(msg).catch((e) => {
    // `code`: "ARPS_TRAPPED" (the engine trapped and re-instantiated itself) or "ARPS_UNUSABLE"
    // (it could not); the client replaces this worker after either.
    post({
      id: msg.id,
      type: "error",
      message: e instanceof Error ? e.message : String(e),
      name: e instanceof Error ? e.name : "Error",
      code: typeof e?.code === "string" ? e.code : undefined,
    });
  });
});
