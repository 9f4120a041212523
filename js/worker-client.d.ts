import type {
  CloudInput,
  CloudWithOrigin,
  ModelConfig,
  ModelProvenance,
  ReadOptions,
  RegisterOptions,
  RegistrationResult,
  RegistrationStage,
  ScanInfo,
} from "./arps.js";

/**
 * Progress of a request, in order: `"loading"` (fetching and compiling the engine and the
 * model: reported to `createWorkerRegistrar`'s `onProgress`, and to a request only when it
 * starts a replacement worker, after an abort, a crash or a trap), `"preparing"` (inputs received, registration starting),
 * `"network"` and `"refining"` (the network, then ICP, as the engine starts them),
 * `"done"` (the result is on its way).
 */
export type Stage = "loading" | RegistrationStage | "done";

/** The stages, in order. */
export declare const STAGES: readonly Stage[];

/** Anything with the `Worker` methods the client uses (a DOM `Worker`, or an adapter in tests). */
export interface WorkerLike {
  postMessage(message: unknown, transfer: Transferable[]): void;
  addEventListener(type: "message" | "error", listener: (event: any) => void): void;
  terminate(): void;
}

export interface CreateWorkerRegistrarOptions {
  /**
   * Where the engine's `.wasm` comes from: a URL (string or `URL`), a `Response`, the bytes
   * (`ArrayBuffer` or a view of one) or a compiled `WebAssembly.Module`. Default: `arps_bg.wasm`
   * next to the package's `arps.js` (what bundlers resolve through `new URL(..., import.meta.url)`).
   */
  wasm?: string | URL | Response | ArrayBuffer | ArrayBufferView | WebAssembly.Module;
  /**
   * Where the default model comes from (fetched by the worker in parallel with the engine): a URL
   * (string or `URL`; relative ones resolve against `worker.js`), a `Response` or the bytes.
   * Default: `models/arps-web.safetensors` next to the package's `arps.js`. In Node, it and a
   * path or `file:` URL given are read from disk.
   */
  model?: string | URL | Response | ArrayBuffer | ArrayBufferView;
  /**
   * Custom weights instead of the default model: the bytes of an arps `.safetensors` file (copied
   * to the worker) or its URL (string or `URL`, fetched by the worker; in Node paths and `file:`
   * URLs are read from disk). Rejects with an `Error` naming the URL and HTTP status if the download fails.
   */
  weights?: ArrayBuffer | ArrayBufferView | string | URL;
  /**
   * A worker to use first instead of starting `worker.js` from this package. When it stops (a
   * crash, a trap, an aborted request), later requests start a replacement with `createWorker`,
   * and reject if that is not given.
   */
  worker?: WorkerLike;
  /**
   * Starts a worker running this package's `worker.js` (the first one, and each replacement
   * after a crash, a trap or an abort). Default: `new Worker(new URL("./worker.js",
   * import.meta.url), { type: "module" })`; under Node (no DOM `Worker`), a `worker_threads`
   * Worker running this package's `node-worker.mjs`.
   */
  createWorker?: () => WorkerLike;
  /** Progress of the initial load (`"loading"`). */
  onProgress?: (stage: Stage) => void;
}

/**
 * A request's options (each method's last argument): other keys, a non-boolean `transfer` (a
 * transfer list, as `postMessage` takes one) and `onProgress` on a method other than `register`
 * are refused by name.
 */
export interface WorkerRequestOptions {
  /**
   * Called with each progress stage of this request. If it throws, the request rejects with an
   * `Error` "onProgress threw: ..." (the error as its `cause`); the worker's answer is dropped.
   */
  onProgress?: (stage: Stage) => void;
  /**
   * Transfer the input buffers to the worker instead of copying them (faster for big clouds;
   * the caller's arrays, a `{ points, origin }` cloud's `points` included, become detached,
   * length 0). Default `false`.
   */
  transfer?: boolean;
  /**
   * Cancels the request: when it aborts, the promise rejects at once with the signal's reason,
   * as `fetch` does (a `DOMException` named `"AbortError"` from `abort()`, `"TimeoutError"` from
   * `AbortSignal.timeout`, or the value given to `abort(reason)`). Requests run one at a time,
   * in call order: one that waits behind another is dropped alone. The engine cannot be
   * interrupted mid-call, so aborting the running request stops the worker, and the requests
   * waiting go to a new one (paying the `"loading"` stage again).
   */
  signal?: AbortSignal;
}

/** A registrar living in a worker; every method returns a promise. */
export interface WorkerRegistrar {
  /** How the loaded weights were made; `kind: "random"` means an untrained placeholder. */
  readonly provenance: ModelProvenance;
  /** The network sizes of the loaded weights. */
  readonly modelConfig: ModelConfig;
  /**
   * Registers `source` onto `target` (packed xyz `[x0, y0, z0, x1, ...]`, the same units; see
   * `CloudInput` for large coordinates) in the worker. Resolves to the same plain object as `Registrar.register`.
   * Rejects with an `Error` carrying the
   * engine's message; the registrar stays usable. After a wasm trap (an engine bug or out of
   * memory) the error has `code: "ARPS_TRAPPED"`, and the worker is replaced: the next request
   * starts a fresh one. Nothing is retried behind your back. The inputs are copied (or, with
   * `transfer`, transferred) during the call, as `postMessage` does, so the caller may refill
   * its arrays once it returns. A `source`/`target` that cannot be sent (`postMessage` throws,
   * e.g. a function in the options) rejects with an `Error` named as what was thrown
   * (`"DataCloneError"`; `"TypeError"` for a buffer that cannot be transferred).
   */
  register(
    source: CloudInput,
    target: CloudInput,
    options?: RegisterOptions | null,
    request?: WorkerRequestOptions,
  ): Promise<RegistrationResult>;
  /**
   * Reads a point cloud from a file's bytes in the worker (format from the file's signature,
   * else its name's extension, else sniffed; `readOptions.surfacePoints` samples a mesh's surface, see
   * `ReadOptions`). Resolves to packed xyz.
   */
  parsePointCloud(
    bytes: ArrayBuffer | ArrayBufferView,
    fileName: string,
    readOptions?: ReadOptions | null,
    request?: { transfer?: boolean; signal?: AbortSignal },
  ): Promise<Float32Array>;
  /**
   * Reads a point cloud in the worker as `{ points, origin }`, keeping large coordinates'
   * precision (see `readPointCloud` in arps.d.ts; `readOptions` as for `parsePointCloud`);
   * `register` takes the object as is.
   */
  readPointCloud(
    bytes: ArrayBuffer | ArrayBufferView,
    fileName: string,
    readOptions?: ReadOptions | null,
    request?: { transfer?: boolean; signal?: AbortSignal },
  ): Promise<CloudWithOrigin>;
  /**
   * Moves a cloud by a rigid 4x4 (or one times a uniform scale) in the worker, its origin in f64 (see `transformPointCloud` in
   * arps.d.ts): e.g. a registered source by its result's `T_target_source` into the target's frame.
   */
  transformPointCloud(
    cloud: CloudInput,
    matrix: ArrayLike<number> | number[][],
    request?: { transfer?: boolean; signal?: AbortSignal },
  ): Promise<CloudWithOrigin>;
  /**
   * A cloud as binary PLY bytes, written in the worker (see `writePly` in arps.d.ts: `double`
   * coordinates when it has an origin away from zero).
   */
  writePly(cloud: CloudInput, request?: { transfer?: boolean; signal?: AbortSignal }): Promise<Uint8Array>;
  /**
   * The scans of an E57 file, in the worker (see `listScans` in arps.d.ts; `[]` for other
   * formats): choose one, then `readPointCloud(bytes, fileName, { scan: K })`.
   */
  listScans(
    bytes: ArrayBuffer | ArrayBufferView,
    fileName: string,
    request?: { transfer?: boolean; signal?: AbortSignal },
  ): Promise<ScanInfo[]>;
  /**
   * A file moved as it is, in its own format, in the worker (see `transformFile` in arps.d.ts:
   * PLY, PCD, XYZ/PTS/TXT/CSV, OBJ, OFF, STL, LAS, LAZ, E57 by its poses, glTF/GLB; every attribute
   * kept, normals turned): e.g. a registered source's file by its `T_target_source`. `readOptions`:
   * those the cloud was read with (`{ scan: K }`: an E57 file's scan alone, as an E57 file of its
   * own). Rejects for a format it cannot tell (save its points: `writePly(await
   * transformPointCloud(cloud, T))`).
   */
  transformFile(
    bytes: ArrayBuffer | ArrayBufferView,
    fileName: string,
    matrix: ArrayLike<number> | number[][],
    readOptions?: ReadOptions | null,
    request?: { transfer?: boolean; signal?: AbortSignal },
  ): Promise<Uint8Array>;
  /**
   * Gives back the memory of the target the worker's registrar keeps prepared for the next
   * `register` onto the same points (see `Registrar.forgetTarget` in arps.d.ts); the next
   * registration prepares its target afresh.
   */
  forgetTarget(request?: { signal?: AbortSignal }): Promise<void>;
  /** Stops the worker; pending and later requests reject. */
  terminate(): void;
}

/**
 * Starts the arps worker, loads the engine and the model in it, and resolves once it is ready.
 * Rejects (and stops the worker) if the engine or the weights cannot be loaded.
 */
export declare function createWorkerRegistrar(options?: CreateWorkerRegistrarOptions): Promise<WorkerRegistrar>;
