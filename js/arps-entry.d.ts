// Declarations of the package entries' own functions (scripts/build-pkg.sh appends them to the
// generated arps.d.ts, replacing the glue's init/initSync): init/initSync with the default model,
// and Registrar's withDefaultModel/fromUrl, which the facade (js/facade.js) provides over the
// engine's fromBytes.

/** A model file: its URL, a `Request`, a `Response`, or its bytes. */
export type ModelSource = string | URL | Request | Response | ArrayBuffer | ArrayBufferView;

/** Options of `init()`. */
export interface InitOptions {
  /** The engine: a URL, `Response`, bytes or `WebAssembly.Module`. Default: `arps_bg.wasm` next to the package's entry. */
  module_or_path?: InitInput | Promise<InitInput>;
  /**
   * The default model, what `Registrar.withDefaultModel()` uses, fetched in parallel with the
   * engine. `true` (the default): `models/arps-web.safetensors` next to the package's entry (a
   * bundler emits it as an asset; browsers cache it like any static file); a URL, `Request`,
   * `Response` or bytes: that file; `false`: none (only `Registrar.fromBytes`/`fromUrl` will be
   * used). In Node the package's default model is read from disk when first needed: a URL, path or
   * bytes given here replace it, `true` and `false` change nothing.
   */
  model?: boolean | ModelSource | Promise<ModelSource>;
}

/**
 * Loads and instantiates the engine and, in parallel, the default model (see `InitOptions`). Call
 * once and await it before anything else (in Node it need not be called). Rejects with an `Error`
 * that names the URL and the HTTP status when the model cannot be fetched, or that says the file
 * is not a valid arps weights file. Passing the engine's `InitInput` directly still works. What it
 * resolves to is not part of the API (it differs between the web and the Node builds): await it,
 * then use the package's exports.
 */
export default function init(options?: InitOptions | InitInput | Promise<InitInput>): Promise<unknown>;

/**
 * `init` synchronously, from the engine's bytes or compiled module; `model`: the default model's
 * bytes (nothing is fetched: without it, `Registrar.withDefaultModel()` throws).
 */
export function initSync(options: { module: SyncInitInput; model?: ArrayBuffer | ArrayBufferView } | SyncInitInput): unknown;

/** Options of `Registrar.fromUrl`. */
export interface FromUrlOptions {
  /** Aborts the download: the promise rejects with the signal's reason (an `AbortError`). */
  signal?: AbortSignal | null;
}

export declare namespace Registrar {
  /**
   * A registrar on the package's default model: the one `await init()` fetched (or, in Node, the
   * package's `models/arps-web.safetensors`, read from disk on first use). In the browser, throws
   * an `Error` if it is not loaded (`init()` not awaited yet, or called with `{ model: false }`).
   */
  function withDefaultModel(): Registrar;
  /**
   * A registrar on the weights file at `url` (an arps `.safetensors`, any precision), fetched
   * (in Node, `file:` URLs and paths are read from disk). Rejects with an `Error` naming the URL
   * and the HTTP status when the download fails, or saying that it is not a valid arps weights
   * file; with an `AbortError` when `signal` aborts.
   */
  function fromUrl(url: string | URL, options?: FromUrlOptions): Promise<Registrar>;
}
