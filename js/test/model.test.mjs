// The default model as its own file (pkg/models/arps-web.safetensors): init() fetches it next to
// the engine, withDefaultModel() before and after, init({ model: false }), Registrar.fromUrl over
// HTTP and file: URLs with clear errors (HTTP status, URL, not a weights file, abort), the Node
// build reading it from disk, and the worker's `weights` URL.
// Run after scripts/build-pkg.sh: node --test js/test/
import test from "node:test";
import assert from "node:assert/strict";
import { readFileSync } from "node:fs";
import http from "node:http";
import path from "node:path";
import { pathToFileURL } from "node:url";
import { pkg, source, target, errors } from "./common.mjs";

const wasmFile = path.join(pkg, "arps_bg.wasm");
const modelFile = path.join(pkg, "models", "arps-web.safetensors");
const wasm = readFileSync(wasmFile);
const model = readFileSync(modelFile);

/** A fresh instance of the web entry (its own facade state; the glue module is shared). */
let fresh = 0;
const webEntry = () => import(`${pathToFileURL(path.join(pkg, "arps.js")).href}?instance=${++fresh}`);

/** The registrar registers the fixture pair (ground truth recovered). */
function registers(r) {
  const res = r.register(source(), target(), { icp: "plane" });
  const e = errors(res.T_target_source);
  assert.ok(e.rot < 2 && e.tr < 0.05, `rotation error ${e.rot} deg, translation error ${e.tr}`);
}

/** A local HTTP server: the model, a 404, a file that is not a model, and a slow response. */
async function server() {
  const s = http.createServer((req, res) => {
    if (req.url === "/models/arps-web.safetensors") {
      res.writeHead(200, { "content-type": "application/octet-stream" }).end(model);
    } else if (req.url === "/spa/model.safetensors") {
      // a dev server's fallback: its index page for a path it does not have
      res.writeHead(200, { "content-type": "text/html" }).end("<!doctype html>\n<html><body>app</body></html>");
    } else if (req.url === "/garbage.safetensors") {
      res.writeHead(200).end("definitely not safetensors");
    } else if (req.url === "/slow.safetensors") {
      res.writeHead(200);
      res.write(model.subarray(0, 1000)); // and never the rest
    } else {
      res.writeHead(404, "Not Found").end();
    }
  });
  await new Promise((resolve) => s.listen(0, "127.0.0.1", resolve));
  s.base = `http://127.0.0.1:${s.address().port}`;
  return s;
}

// Before anything instantiates the engine in this process (the glue module is shared), so that
// init() fetches it: an engine answered by a page fails saying so, and init() works later.
test("web build: an engine answered by an HTML page rejects init() saying so, with the dev server's fix", async () => {
  const arps = await webEntry();
  const page = new Response("<!doctype html><html><body>app</body></html>", { headers: { "content-type": "text/html" } });
  await assert.rejects(arps.default({ module_or_path: page, model: false }), (e) => {
    assert.match(e.message, /^arps: the engine .* is not WebAssembly \(/);
    assert.match(e.message, /optimizeDeps: \{ exclude: \["arps"\] \}/);
    return true;
  });
});

// First to load the engine (so it is not instantiated yet in this process): a bare `init()`
// fetches the engine and the default model next to arps.js, in parallel, through `fetch`.
test("web build: init() fetches arps_bg.wasm and models/arps-web.safetensors next to it", async () => {
  const arps = await webEntry();
  assert.throws(() => arps.Registrar.withDefaultModel(), /^Error: arps: the engine is not loaded yet; call and await init\(\) first$/);
  const realFetch = globalThis.fetch;
  const requested = [];
  let inFlight = 0;
  let overlapped = false;
  globalThis.fetch = async (url) => {
    const u = new URL(String(url instanceof Request ? url.url : url));
    requested.push(u.href);
    inFlight++;
    if (inFlight > 1) overlapped = true;
    await new Promise((resolve) => setTimeout(resolve, 50));
    inFlight--;
    const body = readFileSync(u);
    return new Response(body, { headers: { "content-type": u.pathname.endsWith(".wasm") ? "application/wasm" : "application/octet-stream" } });
  };
  try {
    await arps.default();
  } finally {
    globalThis.fetch = realFetch;
  }
  assert.deepEqual(requested.sort(), [pathToFileURL(wasmFile).href, pathToFileURL(modelFile).href].sort());
  assert.ok(overlapped, "the engine and the model are fetched in parallel");
  const r = arps.Registrar.withDefaultModel();
  assert.equal(r.modelConfig.preset, "web");
  registers(r);
  r.free();
});

test("web build: a failed default-model fetch rejects init() with the URL and the HTTP status", async () => {
  const arps = await webEntry();
  const realFetch = globalThis.fetch;
  globalThis.fetch = async (url) => new Response("nope", { status: 404, statusText: "Not Found" });
  try {
    await assert.rejects(arps.default({ module_or_path: wasm }), (e) => {
      assert.match(e.message, /^arps: fetching the model .*\/models\/arps-web\.safetensors failed: /);
      assert.match(e.message, /init\(\{ model: false \}\) skips the default model/);
      return true;
    });
  } finally {
    globalThis.fetch = realFetch;
  }
  // The engine is loaded all the same; the default model is not.
  assert.throws(() => arps.Registrar.withDefaultModel(), /^Error: arps: the default model is not loaded: `await init\(\)` fetches it/);
  // A Response that is not ok, given as the model, says its status.
  await assert.rejects(arps.default({ model: new Response("x", { status: 503, statusText: "Service Unavailable" }) }), /HTTP 503 Service Unavailable/);
});

test("web build: init({ model: false }), withDefaultModel before and after, fromUrl and its errors", async () => {
  const s = await server();
  try {
    const arps = await webEntry();
    await arps.default({ module_or_path: wasm, model: false });
    assert.throws(() => arps.Registrar.withDefaultModel(), /^Error: arps: the default model is not loaded: .*\{ model: false \}.*Registrar\.fromUrl/);
    // fromUrl over HTTP.
    const r = await arps.Registrar.fromUrl(`${s.base}/models/arps-web.safetensors`);
    registers(r);
    r.free();
    const r2 = await arps.Registrar.fromUrl(new URL("/models/arps-web.safetensors", s.base), { signal: new AbortController().signal });
    assert.equal(r2.modelConfig.preset, "web");
    r2.free();
    // Errors: HTTP status and URL; not a weights file; not a URL; unreachable; aborted.
    await assert.rejects(arps.Registrar.fromUrl(`${s.base}/missing.safetensors`), {
      message: `arps: fetching the model ${s.base}/missing.safetensors failed: HTTP 404 Not Found`,
    });
    await assert.rejects(
      arps.Registrar.fromUrl(`${s.base}/garbage.safetensors`),
      new RegExp(`^Error: arps: ${s.base}/garbage\\.safetensors is not a valid arps weights file \\(weights: not a valid safetensors file`),
    );
    await assert.rejects(
      arps.Registrar.fromUrl(`${s.base}/spa/model.safetensors`),
      new RegExp(`^Error: arps: the model ${s.base}/spa/model\\.safetensors is an HTML page, not an arps weights file`),
    );
    await assert.rejects(arps.Registrar.fromUrl(42), /^Error: fromUrl: expected a URL \(string or URL\), got a number$/);
    await assert.rejects(arps.Registrar.fromUrl("http://127.0.0.1:1/x.safetensors"), /^Error: arps: fetching the model http:\/\/127\.0\.0\.1:1\/x\.safetensors failed: TypeError/);
    const before = new AbortController();
    before.abort();
    await assert.rejects(arps.Registrar.fromUrl(`${s.base}/models/arps-web.safetensors`, { signal: before.signal }), { name: "AbortError" });
    const during = new AbortController();
    const slow = arps.Registrar.fromUrl(`${s.base}/slow.safetensors`, { signal: during.signal });
    setTimeout(() => during.abort(), 100);
    await assert.rejects(slow, { name: "AbortError" });
    // After all that the instance works, and init({ model: url }) sets the default model.
    await arps.default({ model: `${s.base}/models/arps-web.safetensors` });
    const d = arps.Registrar.withDefaultModel();
    registers(d);
    d.free();
    // A model that does not load is refused by init, naming where it came from.
    await assert.rejects(arps.default({ model: new Uint8Array([1, 2, 3]) }), /^Error: arps: the model given to init\(\) is not a valid arps weights file \(weights: /);
  } finally {
    s.close();
  }
});

test("web build: initSync({ module, model }) and initSync without a model", async () => {
  const a = await webEntry();
  a.initSync({ module: wasm });
  assert.throws(() => a.Registrar.withDefaultModel(), /the default model is not loaded/);
  a.initSync({ module: wasm, model });
  registers(a.Registrar.withDefaultModel());
});

test("node build: the default model from disk, fromUrl on file: and http: URLs", async () => {
  const arps = await import(pathToFileURL(path.join(pkg, "node", "index.mjs")).href);
  await arps.default({ model: false }); // nothing to skip in Node: the model is read on first use
  registers(arps.Registrar.withDefaultModel());
  const r = await arps.Registrar.fromUrl(pathToFileURL(modelFile));
  registers(r);
  const missing = pathToFileURL(path.join(pkg, "models", "missing.safetensors")).href;
  await assert.rejects(arps.Registrar.fromUrl(missing), new RegExp(`^Error: arps: reading the model ${missing} failed: ENOENT`));
  const s = await server();
  try {
    registers(await arps.Registrar.fromUrl(`${s.base}/models/arps-web.safetensors`));
    await assert.rejects(arps.Registrar.fromUrl(`${s.base}/nothing`), /HTTP 404/);
  } finally {
    s.close();
  }
});

test("worker: weights as a URL (file: in Node), and a clear error for a failed download", async () => {
  const { createWorkerRegistrar } = await import(pathToFileURL(path.join(pkg, "worker-client.js")).href);
  const arps = await createWorkerRegistrar({ weights: pathToFileURL(modelFile) });
  try {
    assert.equal(arps.modelConfig.preset, "web");
    const res = await arps.register(source(), target(), { icp: "plane" });
    const e = errors(res.T_target_source);
    assert.ok(e.rot < 2 && e.tr < 0.05, `rotation error ${e.rot} deg`);
  } finally {
    arps.terminate();
  }
  const s = await server();
  try {
    await assert.rejects(createWorkerRegistrar({ weights: `${s.base}/missing.safetensors` }), /fetching the model .*\/missing\.safetensors failed: HTTP 404/);
  } finally {
    s.close();
  }
});
