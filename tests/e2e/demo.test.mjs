// End-to-end test of the demo page (www/) in Debian's Chromium, headless, through playwright-core.
// Needs the built package (scripts/build-pkg.sh) and the npm dev dependencies; run it with
// scripts/test-e2e.sh. Screenshots go to $ARPS_E2E_OUT (default target/e2e/): demo.png,
// example.png, box-alternative.png (a box pair's first alternative pose shown), survey.png (a LAZ
// survey aligned in map-grid coordinates), big-1400x860.png and
// big-390x844.png (the 1M-point pair's result, desktop and phone).
//
// The known-transform pair: two half-space crops (85% each) of the committed Velodyne fixture
// (fixtures/scans/velodyne-small.ply, MIT), the target moved by 15 degrees about a near-vertical
// axis plus (1.0, -0.6, 0.2) m. A modest motion on purpose: the embedded default model may still be
// an untrained placeholder, and ICP alone recovers this one.
//
// The 1M-point pair: the same crops densified to 1,000,000 points each (every fixture point
// repeated with independent jitter, about 0.08 m, different seeds for source and target), written
// as binary PLY and uploaded like the small pair. Both pairs come from ./street-pair.mjs, which
// also writes them to disk for `arps register` (`node tests/e2e/street-pair.mjs DIR 1000000`).
// The main thread's long tasks (Chromium's `longtask` performance entries, > 50 ms) are recorded
// while loading, fitting and aligning it.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { mkdirSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from "node:fs";
import { tmpdir } from "node:os";
import { dirname, join, resolve } from "node:path";
import { fileURLToPath, pathToFileURL } from "node:url";
import { chromium } from "playwright-core";
import { PNG } from "pngjs";
import { serve } from "../../scripts/serve.mjs";
import {
  bounds,
  confidenceWords,
  decimate,
  invertRigid,
  modelSummary,
  multiply,
  parameterCount,
  rigid,
  relativeTo,
  rotationAngleDeg,
  transformBounds,
  transformPoints,
  hasOrigin,
  writePly,
} from "../../www/lib.js";
import { readFloatPly, streetCrops, streetPair, TRUTH } from "./street-pair.mjs";

const ROOT = resolve(dirname(fileURLToPath(import.meta.url)), "../..");
const CHROMIUM = process.env.ARPS_CHROMIUM ?? "/usr/bin/chromium";
const OUT = resolve(ROOT, process.env.ARPS_E2E_OUT ?? "target/e2e");
const TIMEOUT = 120_000;

const BIG = 1_000_000;
/** The longest main-thread task allowed while loading, fitting or aligning the 1M-point pair. */
const LONGEST_TASK_MS = 200;
const DESKTOP = { width: 1400, height: 860 };
const PHONE = { width: 390, height: 844 };

/** The box pair's truth (column-major): 30 degrees about z, then (0.4, -0.2, 0.1). */
const BOX_TRUTH = (() => {
  const a = (30 * Math.PI) / 180;
  return [Math.cos(a), Math.sin(a), 0, 0, -Math.sin(a), Math.cos(a), 0, 0, 0, 0, 1, 0, 0.4, -0.2, 0.1, 1];
})();

/**
 * An ASCII PLY of points on a box with half-extents 1, 0.6 and 0.35 (its half turns about its axes
 * fit it as well as the truth), on a grid of `step` shifted by `offset`, moved by `m` (column-major)
 * unless null.
 */
function boxPly(step, offset, m) {
  const h = [1, 0.6, 0.35];
  const lines = [];
  for (let k = 0; k < 3; k++) {
    const [a, b] = [(k + 1) % 3, (k + 2) % 3];
    for (const side of [-1, 1]) {
      for (let u = -h[a] + offset; u <= h[a]; u += step) {
        for (let v = -h[b] + offset; v <= h[b]; v += step) {
          const p = [0, 0, 0];
          [p[k], p[a], p[b]] = [side * h[k], u, v];
          const q = m ? [0, 1, 2].map((r) => m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r]) : p;
          lines.push(q.map((x) => x.toFixed(6)).join(" "));
        }
      }
    }
  }
  const header = ["ply", "format ascii 1.0", `element vertex ${lines.length}`, "property float x", "property float y", "property float z", "end_header"];
  return [...header, ...lines, ""].join("\n");
}

let server;
let url;
let browser;
let page;
let dir;
const consoleLines = [];

before(async () => {
  dir = mkdtempSync(join(tmpdir(), "arps-e2e-"));
  const small = streetPair();
  writeFileSync(join(dir, "source.ply"), small.source);
  writeFileSync(join(dir, "target.ply"), small.target);
  const big = streetPair(BIG);
  writeFileSync(join(dir, "big-source.ply"), big.source);
  writeFileSync(join(dir, "big-target.ply"), big.target);
  writeFileSync(join(dir, "box-source.ply"), boxPly(0.05, 0, null));
  writeFileSync(join(dir, "box-target.ply"), boxPly(0.05, 0.01, BOX_TRUTH));
  writeFileSync(join(dir, "broken.ply"), "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\nnot numbers\n");

  ({ server, url } = await serve({ port: 0 }));
  // A fresh profile (--user-data-dir) in the temp dir, through playwright's persistent context.
  browser = await chromium.launchPersistentContext(join(dir, "profile"), {
    executablePath: CHROMIUM,
    viewport: DESKTOP,
    headless: true,
    args: [
      "--no-sandbox",
      "--disable-gpu",
      "--disable-quic",
      "--no-first-run",
      "--disable-background-networking",
      "--disable-component-update",
      "--disable-sync",
      "--enable-unsafe-swiftshader",
    ],
  });
  page = browser.pages()[0] ?? (await browser.newPage());
  page.on("console", (m) => consoleLines.push(`console.${m.type()}: ${m.text()}`));
  page.on("pageerror", (e) => consoleLines.push(`pageerror: ${e.message}`));
  // Every main-thread task over 50 ms, as [startTime, duration] (ms, page clock).
  await page.addInitScript(() => {
    window.__longTasks = [];
    new PerformanceObserver((list) => {
      for (const e of list.getEntries()) window.__longTasks.push([e.startTime, e.duration]);
    }).observe({ type: "longtask", buffered: true });
  });
  await page.goto(url);
  await page.waitForFunction(() => /engine ready/.test(document.getElementById("engine-status").textContent), null, {
    timeout: TIMEOUT,
  });
});

after(async () => {
  if (consoleLines.length) console.log(consoleLines.join("\n"));
  await browser?.close();
  server?.close();
  if (dir) rmSync(dir, { recursive: true, force: true });
});

/** Clicks Align and waits for #result or #error; returns { result, error }. */
async function alignAndWait() {
  await page.waitForFunction(() => !document.getElementById("align").disabled, null, { timeout: TIMEOUT });
  await page.click("#align");
  await page.waitForFunction(
    () => document.getElementById("result").textContent.trim() || document.getElementById("error").textContent.trim(),
    null,
    { timeout: TIMEOUT },
  );
  const result = (await page.textContent("#result")).trim();
  const error = (await page.textContent("#error")).trim();
  return { result: result ? JSON.parse(result) : null, error };
}

async function uploadPair() {
  await page.setInputFiles("#source-file", join(dir, "source.ply"));
  await page.waitForFunction(() => /points/.test(document.getElementById("source-info").textContent), null, { timeout: TIMEOUT });
  await page.setInputFiles("#target-file", join(dir, "target.ply"));
  await page.waitForFunction(() => /points/.test(document.getElementById("target-info").textContent), null, { timeout: TIMEOUT });
}

function errorsAgainstTruth(result, truth = TRUTH) {
  const rows = result.T_target_source;
  assert.equal(rows.length, 4);
  const m = new Float64Array(16);
  for (let r = 0; r < 4; r++) for (let c = 0; c < 4; c++) m[c * 4 + r] = rows[r][c];
  const err = multiply(invertRigid(truth), m);
  return { rotationDeg: rotationAngleDeg(err), translation: Math.hypot(err[12], err[13], err[14]) };
}

test("aligns two uploaded scans with a known transform", { timeout: TIMEOUT * 2 }, async () => {
  await uploadPair();
  const { result, error } = await alignAndWait();
  assert.equal(error, "", `unexpected #error: ${error}`);
  const e = errorsAgainstTruth(result);
  console.log(
    `known transform (15 deg): rotation error ${e.rotationDeg.toFixed(3)} deg, translation error ${e.translation.toFixed(4)} m, ` +
      `fitness ${result.fitness.toFixed(3)}, confidence ${result.confidence.toFixed(3)}, ${result.timings.totalMs.toFixed(0)} ms`,
  );
  assert.ok(e.rotationDeg < 5, `rotation error ${e.rotationDeg} deg`);
  assert.ok(e.translation < 0.25, `translation error ${e.translation} m (scene about 60 m across)`);
  assert.ok(result.fitness > 0.3, `fitness ${result.fitness}`);
  // The page's own figures agree with the matrix.
  assert.ok(Math.abs(result.rotationDeg - 15) < 5, `page says ${result.rotationDeg} deg`);
  // The engine's confidence, in words next to the figures, agrees with the result.
  assert.ok(result.confidence >= 0 && result.confidence <= 1, `confidence ${result.confidence}`);
  assert.equal(typeof result.evidence.overlapReverse, "number");
  assert.ok(result.startsRefined >= 1, `startsRefined ${result.startsRefined}`);
  const verdict = (await page.textContent("#verdict")).trim();
  assert.equal(verdict, confidenceWords(result.confidence, result.alternatives.length).words);
  assert.match(verdict, /^(likely right|uncertain|likely wrong|ambiguous) \(confidence [01]\.\d\d\)/);
  assert.match(await page.textContent("#units-help"), /your scans' own units/);
  // Each of fitness and inlier RMSE comes with its explanation, in the scan's units.
  const figures = await page.$$eval("#figures dt", (dts) => dts.map((dt) => [dt.textContent, dt.nextElementSibling.textContent]));
  const fitness = figures.find(([k]) => k === "Fitness")[1];
  const rmse = figures.find(([k]) => k === "Inlier RMSE")[1];
  assert.match(fitness, /% of source points within [\d.]+ units.*max correspondence distance/);
  assert.match(rmse, /^[\d.e-]+ units.*root mean square/);
  // The pose buttons show only when the result offers other poses.
  assert.equal(await page.isHidden("#alternatives"), result.alternatives.length === 0);
});

test("confidence in words: thresholds at 0.8 and 0.5", () => {
  assert.deepEqual(confidenceWords(0.93), { words: "likely right (confidence 0.93)", level: "right" });
  assert.deepEqual(confidenceWords(0.8), { words: "likely right (confidence 0.80)", level: "right" });
  assert.deepEqual(confidenceWords(0.62), { words: "uncertain (confidence 0.62)", level: "uncertain" });
  assert.deepEqual(confidenceWords(0.12), { words: "likely wrong (confidence 0.12)", level: "wrong" });
  // with look-alike poses, below 0.8: ambiguous, the level still by the figure
  assert.deepEqual(confidenceWords(0.25, 2), { words: "ambiguous (confidence 0.25): 2 other poses fit about as well", level: "wrong" });
  assert.deepEqual(confidenceWords(0.5, 1), { words: "ambiguous (confidence 0.50): 1 other pose fit about as well", level: "uncertain" });
  assert.deepEqual(confidenceWords(0.9, 1), { words: "likely right (confidence 0.90)", level: "right" });
  assert.equal(confidenceWords(undefined).level, "uncertain");
});

/** The shipped model's config, camelCase as the engine reports it, from the weights file's header. */
function shippedModelConfig() {
  const buf = readFileSync(join(ROOT, "models/web.safetensors"));
  const meta = JSON.parse(buf.subarray(8, 8 + Number(buf.readBigUInt64LE(0))).toString()).__metadata__;
  const c = JSON.parse(meta.config);
  const camel = Object.fromEntries(Object.entries(c).map(([k, v]) => [k.replace(/_(\w)/g, (_, ch) => ch.toUpperCase()), v]));
  return { config: camel, provenance: JSON.parse(meta.provenance ?? "{}") };
}

test("page helpers: drawn subsample, bounds, parameter count, model in words", () => {
  const n = 50_000;
  const pts = new Float32Array(n * 3).map((_, i) => (i % 3) + i / (3 * n)); // x in [0,1), y in [1,2), z in [2,3)
  for (let i = 350; i < 400; i++) pts[3 * i + 1] = NaN; // the 8th run of 50: whichever is picked is skipped
  const drawn = decimate(pts, 1000, 3);
  assert.equal(drawn.length, 3 * 999, "one point from each of the 1000 runs, but none from the non-finite one");
  assert.ok(drawn.every(Number.isFinite));
  // Stratified: the i-th drawn point comes from the i-th run of 50 input points.
  assert.ok(Math.abs(drawn[3 * 500] - 0.5) < 0.002, `middle drawn point at x = ${drawn[3 * 500]}`);
  assert.deepEqual(decimate(pts, 1000, 3), drawn, "seeded");
  assert.equal(decimate(pts.subarray(3 * 395, 3 * 405), 1000).length, 15, "few points: all the finite ones");
  const b = bounds(pts);
  assert.ok(b.min[0] >= 0 && b.min[0] < 1e-4 && b.max[2] > 2.99 && b.max[2] < 3);
  assert.equal(bounds(new Float32Array([NaN, 0, 0])), null);
  const turned = transformBounds({ min: [0, 0, 0], max: [1, 2, 3] }, rigid([0, 0, 1], 90, [1, 0, 0]));
  assert.deepEqual(turned.min.map((v) => Math.round(v * 1e6) / 1e6), [-1, 0, 0]);
  assert.deepEqual(turned.max.map((v) => Math.round(v * 1e6) / 1e6), [1, 1, 3]);

  // The scene's matrix: a motion between absolute frames (map-grid coordinates) acting on
  // offsets from one origin and giving offsets from another near the moved points, in f64.
  const origin = [4_512_345.25, 5_612_345.5, 1234.125];
  const offsets = new Float32Array([0.5, -1.25, 2, 10.75, 3.5, -0.5]);
  const T = rigid([0.2, 0.1, 1], 33, [-7.5, 12.25, 0.75]);
  const absolute = (i) => [0, 1, 2].map((k) => origin[k] + offsets[i + k]);
  const moved = (i) => [0, 1, 2].map((r) => T[r] * absolute(i)[0] + T[4 + r] * absolute(i)[1] + T[8 + r] * absolute(i)[2] + T[12 + r]);
  const other = moved(0).map((v, k) => Math.round(v) + [-40, 30, -5][k]); // near the moved points
  const scene = transformPoints(offsets, relativeTo(T, origin, other));
  for (let i = 0; i < 6; i += 3) {
    for (let r = 0; r < 3; r++) assert.ok(Math.abs(scene[i + r] + other[r] - moved(i)[r]) < 1e-4, `scene point ${i / 3}, axis ${r}`);
  }
  assert.equal(hasOrigin([0, 0, 0]), false);
  assert.equal(hasOrigin(null), false);
  assert.equal(hasOrigin(origin), true);

  // The count the engine's ModelConfig::parameter_count gives the shipped model (models/MODEL.md).
  const { config, provenance } = shippedModelConfig();
  assert.equal(parameterCount(config), 1_162_200);
  const words = modelSummary(provenance, config);
  assert.match(words.label, /^model “web” · 1\.16 M parameters$/);
  assert.doesNotMatch(words.about, /[{}"\/\\]/, "no JSON, no paths");
  assert.equal(modelSummary({ kind: "random" }, config).untrained, true);
  assert.doesNotMatch(modelSummary({ run: "../../etc/x", data: { bank: "/home/me/meshes" } }, config).about, /\//);
});

test("the engine badge names the model, its size and training in words", async () => {
  const label = (await page.textContent("#engine-status")).trim();
  const about = (await page.textContent("#engine-about")).trim();
  console.log(`badge: ${label}\n  ${about}`);
  assert.match(label, /^engine ready · (model “\w+” · [\d.]+ M parameters|untrained placeholder model)$/);
  assert.ok(about.length > 40, about);
  assert.doesNotMatch(about + (await page.getAttribute("#engine-status", "title")), /[{}\/\\]|":/, "no raw JSON, no paths");
  if (!/untrained/.test(label)) assert.match(about, /parameters.*Trained.* for [\d,]+ steps on [\d,]+ synthetic/);
});

test("the long-task observer sees a task that blocks the main thread", async () => {
  const t0 = await page.evaluate(() => performance.now());
  await page.evaluate(
    () =>
      new Promise((resolve) =>
        setTimeout(() => {
          const t = performance.now();
          while (performance.now() - t < 150);
          setTimeout(resolve, 100);
        }),
      ),
  );
  await page.waitForTimeout(200);
  const tasks = await longTasksSince(t0);
  assert.ok(tasks.some(([, d]) => d >= 140), `long tasks seen: ${JSON.stringify(tasks)}`);
});

test("download the aligned source as PLY; copy the matrix as JSON", async () => {
  const result = JSON.parse(await page.textContent("#result"));
  const [download] = await Promise.all([page.waitForEvent("download"), page.click("#download-ply")]);
  assert.equal(download.suggestedFilename(), "source-aligned.ply");
  const file = join(dir, "aligned.ply");
  await download.saveAs(file);
  // a PLY source comes back as its own file moved (its header, comment included, kept)
  assert.match(readFileSync(file).subarray(0, 200).toString("latin1"), /comment street pair source\n/);
  const aligned = readFloatPly(file);
  const source = streetCrops().source;
  assert.equal(aligned.length, source.length);
  // The file holds the source mapped through the result (row-major rows in #result).
  const [r0, r1, r2] = result.T_target_source;
  let worst = 0;
  for (let i = 0; i < source.length; i += 3) {
    const [x, y, z] = [source[i], source[i + 1], source[i + 2]];
    worst = Math.max(
      worst,
      Math.abs(r0[0] * x + r0[1] * y + r0[2] * z + r0[3] - aligned[i]),
      Math.abs(r1[0] * x + r1[1] * y + r1[2] * z + r1[3] - aligned[i + 1]),
      Math.abs(r2[0] * x + r2[1] * y + r2[2] * z + r2[3] - aligned[i + 2]),
    );
  }
  assert.ok(worst < 1e-3, `aligned PLY differs from the result's transform by ${worst}`);

  await browser.grantPermissions(["clipboard-read", "clipboard-write"], { origin: new URL(url).origin });
  await page.click("#copy-matrix");
  await page.waitForFunction(() => /Copied/.test(document.getElementById("copy-matrix").textContent));
  const copied = JSON.parse(await page.evaluate(() => navigator.clipboard.readText()));
  assert.deepEqual(copied, { T_target_source: result.T_target_source });
});

test("the view is not blank (screenshot)", async () => {
  mkdirSync(OUT, { recursive: true });
  await viewUpToDate();
  await page.screenshot({ path: join(OUT, "demo.png") });
  const png = PNG.sync.read(await page.locator("#canvas").screenshot());
  const bg = [0x0f, 0x17, 0x2a]; // the scene's background (www/scene.js)
  let lit = 0;
  for (let i = 0; i < png.data.length; i += 4) {
    const d = Math.abs(png.data[i] - bg[0]) + Math.abs(png.data[i + 1] - bg[1]) + Math.abs(png.data[i + 2] - bg[2]);
    if (d > 60) lit++;
  }
  const share = lit / (png.width * png.height);
  console.log(`canvas ${png.width}x${png.height}: ${lit} non-background pixels (${(share * 100).toFixed(2)}%); screenshot ${join(OUT, "demo.png")}`);
  assert.ok(lit > 2000, `only ${lit} non-background pixels: the view looks blank`);
});

test("a malformed file shows #error and the page keeps working", { timeout: TIMEOUT * 2 }, async () => {
  // over a good scan: the error says so, and the good scan stays loaded (and its result)
  await uploadPair();
  const before = await page.textContent("#source-info");
  await page.setInputFiles("#source-file", join(dir, "broken.ply"));
  await page.waitForFunction(() => document.getElementById("error").textContent.trim(), null, { timeout: TIMEOUT });
  let message = (await page.textContent("#error")).trim();
  console.log(`#error: ${message}`);
  assert.match(message, /^Could not read broken\.ply: .*\(source\.ply stays loaded\)$/);
  assert.equal(await page.textContent("#source-info"), before);
  assert.ok(await page.isEnabled("#align"), "Align stays enabled with the scans loaded");
  // in an empty slot: Align stays disabled, and says why
  await page.reload();
  await page.waitForFunction(() => /engine ready/.test(document.getElementById("engine-status").textContent), null, { timeout: TIMEOUT });
  await page.setInputFiles("#source-file", join(dir, "broken.ply"));
  await page.waitForFunction(() => document.getElementById("error").textContent.trim(), null, { timeout: TIMEOUT });
  message = (await page.textContent("#error")).trim();
  assert.match(message, /^Could not read broken\.ply: [^(]*$/);
  assert.equal((await page.textContent("#result")).trim(), "");
  assert.ok(await page.isDisabled("#align"), "Align stays disabled without a source");
  assert.equal(await page.getAttribute("#align", "title"), "Load a source and a target scan first");

  // Still usable: a good file again, and Align works.
  await uploadPair();
  assert.equal((await page.textContent("#error")).trim(), "");
  const { result, error } = await alignAndWait();
  assert.equal(error, "");
  assert.ok(errorsAgainstTruth(result).rotationDeg < 5);
});

test("too few points: refused when loaded, the scan before stays", { timeout: TIMEOUT * 2 }, async () => {
  writeFileSync(join(dir, "tiny.xyz"), "0 0 0\n1 0 0\n0 1 0\n");
  await uploadPair();
  const before = await page.textContent("#source-info");
  await page.setInputFiles("#source-file", join(dir, "tiny.xyz"));
  await page.waitForFunction(() => document.getElementById("error").textContent.trim(), null, { timeout: TIMEOUT });
  const message = (await page.textContent("#error")).trim();
  console.log(`#error: ${message}`);
  assert.match(message, /^Could not read tiny\.xyz: it holds 3 points; a registration needs at least 16 \(source\.ply stays loaded\)$/);
  assert.equal(await page.textContent("#source-info"), before);
});

test("the example: bunny views aligned back to the known 20 degree motion", { timeout: TIMEOUT * 2 }, async () => {
  await page.click("#example");
  await page.waitForFunction(() => /bunny/.test(document.getElementById("target-info").textContent), null, { timeout: TIMEOUT });
  const { result, error } = await alignAndWait();
  assert.equal(error, "");
  console.log(
    `example: rotation ${result.rotationDeg.toFixed(2)} deg, error vs truth ${result.exampleError.rotationDeg.toFixed(3)} deg / ${result.exampleError.translation.toFixed(4)}`,
  );
  assert.ok(result.exampleError.rotationDeg < 5);
  await page.screenshot({ path: join(OUT, "example.png") });
});

test("Cancel stops an alignment, and the next one works", { timeout: TIMEOUT * 2 }, async () => {
  await page.waitForFunction(() => !document.getElementById("align").disabled, null, { timeout: TIMEOUT });
  // Align, then Cancel in the same task: the request is cancelled whatever stage it reached.
  await page.evaluate(() => {
    document.getElementById("align").click();
    document.getElementById("cancel").click();
  });
  await page.waitForFunction(() => document.getElementById("error").textContent.trim(), null, { timeout: TIMEOUT });
  assert.equal((await page.textContent("#error")).trim(), "Alignment cancelled.");
  assert.equal((await page.textContent("#result")).trim(), "");
  const { result, error } = await alignAndWait();
  assert.equal(error, "");
  assert.ok(result.exampleError.rotationDeg < 5, "the pair aligns after a cancel");
});

/** The main thread's long tasks ([startTime, duration], ms) that started at or after `t0`. */
async function longTasksSince(t0) {
  return page.evaluate((t) => window.__longTasks.filter(([start]) => start >= t), t0);
}

/** Waits until the view has drawn every change sent to it (the page's test hook on #canvas). */
async function viewUpToDate() {
  await page.waitForFunction(
    () => {
      const { sent, drawn } = document.getElementById("canvas").dataset;
      return sent !== undefined && sent === drawn;
    },
    null,
    { timeout: TIMEOUT },
  );
}

/** The view up to date, then two animation frames and a little time for late tasks. */
async function settle() {
  await viewUpToDate();
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(() => setTimeout(r, 300)))));
}

/** Canvas pixels within a small distance of `rgb`. */
async function pixelsNear(rgb) {
  const png = PNG.sync.read(await page.locator("#canvas").screenshot());
  let n = 0;
  for (let i = 0; i < png.data.length; i += 4) {
    if (Math.abs(png.data[i] - rgb[0]) + Math.abs(png.data[i + 1] - rgb[1]) + Math.abs(png.data[i + 2] - rgb[2]) < 60) n++;
  }
  return n;
}

/** Runs `action` and reports `{ ms, tasks, longest }`: its wall time and the long tasks meanwhile. */
async function measured(action) {
  const t0 = await page.evaluate(() => performance.now());
  const wall = performance.now();
  await action();
  const ms = performance.now() - wall;
  await settle();
  const tasks = await longTasksSince(t0);
  return { ms, tasks: tasks.map(([, d]) => Math.round(d)), longest: Math.max(0, ...tasks.map(([, d]) => d)) };
}

function inViewport(box, viewport) {
  return box && box.x >= 0 && box.y >= 0 && box.x + box.width <= viewport.width && box.y + box.height <= viewport.height;
}

test("a symmetric box: the other poses that fit as well are offered, and picking one shows it", { timeout: TIMEOUT * 2 }, async () => {
  await page.setInputFiles("#source-file", join(dir, "box-source.ply"));
  await page.waitForFunction(() => /box-source/.test(document.getElementById("source-info").textContent), null, { timeout: TIMEOUT });
  await page.setInputFiles("#target-file", join(dir, "box-target.ply"));
  await page.waitForFunction(() => /box-target/.test(document.getElementById("target-info").textContent), null, { timeout: TIMEOUT });
  const { result, error } = await alignAndWait();
  assert.equal(error, "", `unexpected #error: ${error}`);
  assert.equal(result.shown, "answer");
  assert.ok(result.alternatives.length >= 1, "a box fits itself turned: the result offers other poses");
  if (result.confidence < 0.8) assert.match(await page.textContent("#verdict"), /^ambiguous \(confidence [\d.]+\): \d+ other poses? fit about as well$/);
  assert.ok(await page.isVisible("#alternatives"));
  const buttons = page.locator("#alternatives-poses button");
  assert.equal(await buttons.count(), 1 + result.alternatives.length);
  assert.match(await buttons.nth(0).textContent(), /^Answer · fitness [\d.]+%$/);
  // Each pose in turn: the matrix and the result JSON follow it, the pressed button with it.
  const poses = [{ T_target_source: result.T_target_source }, ...result.alternatives];
  const near = [];
  for (let k = poses.length - 1; k >= 0; k--) {
    await buttons.nth(k).click();
    const shown = JSON.parse(await page.textContent("#result"));
    assert.equal(shown.shown, k === 0 ? "answer" : `alternative ${k}`);
    assert.deepEqual(shown.T_target_source, poses[k].T_target_source);
    const cells = await page.$$eval("#matrix td", (tds) => tds.map((td) => Number(td.textContent)));
    // (to four decimals; what rounds to zero is written 0, never -0)
    assert.deepEqual(cells, poses[k].T_target_source.flat().map((v) => Number((Math.abs(v) < 5e-5 ? 0 : v).toFixed(4))));
    assert.equal(await buttons.nth(k).getAttribute("class"), "on");
    const e = errorsAgainstTruth(shown, BOX_TRUTH);
    near.push(e.rotationDeg < 2 && e.translation < 0.02);
  }
  assert.ok(near.some(Boolean), "the truth is the answer or one of the alternatives");
  // The copy follows the pose shown.
  await buttons.nth(1).click();
  await page.screenshot({ path: join(OUT, "box-alternative.png") });
  await page.click("#copy-matrix");
  await page.waitForFunction(() => /Copied/.test(document.getElementById("copy-matrix").textContent));
  const copied = JSON.parse(await page.evaluate(() => navigator.clipboard.readText()));
  assert.deepEqual(copied, { T_target_source: poses[1].T_target_source });
  // Both boxes stand on z: with "Up axis: z" the answer and every pose offered only turn about z
  // (the half turns about x and y are ruled out).
  await page.selectOption("#up", "0,0,1");
  try {
    const upright = await alignAndWait();
    assert.equal(upright.error, "", `unexpected #error: ${upright.error}`);
    const level = (rows) => rows[2][2] >= Math.cos((10 * Math.PI) / 180);
    assert.ok(level(upright.result.T_target_source), JSON.stringify(upright.result.T_target_source));
    for (const a of upright.result.alternatives) assert.ok(level(a.T_target_source), JSON.stringify(a.T_target_source));
    assert.ok(upright.result.alternatives.length < result.alternatives.length, "fewer look-alikes once up is known");
  } finally {
    await page.selectOption("#up", "");
  }
});

test("a scan in metres onto a target in millimetres: the units said, it aligns in millimetres", { timeout: TIMEOUT * 2 }, async () => {
  // The street pair's target written in millimetres; the source stays in metres.
  const mm = readFloatPly(join(dir, "target.ply")).map((v) => v * 1000);
  writeFileSync(join(dir, "target-mm.ply"), writePly(mm, "street pair target in millimetres"));
  await page.setInputFiles("#source-file", join(dir, "source.ply"));
  await page.waitForFunction(() => /source\.ply · [\d,]+ points/.test(document.getElementById("source-info").textContent), null, { timeout: TIMEOUT });
  await page.setInputFiles("#target-file", join(dir, "target-mm.ply"));
  await page.waitForFunction(() => /target-mm\.ply · [\d,]+ points/.test(document.getElementById("target-info").textContent), null, { timeout: TIMEOUT });
  // Units unsaid: the engine warns that the sizes differ.
  let { result, error } = await alignAndWait();
  assert.equal(error, "", `unexpected #error: ${error}`);
  assert.ok(result.warnings.some((w) => /differ in size by \d+x/.test(w)), JSON.stringify(result.warnings));
  assert.match(await page.textContent("#warnings"), /Different units\? Say which under Units/);
  // Said: the source is scaled by 1000 (drawn again, the result cleared), and aligns in millimetres.
  await page.selectOption("#target-unit", "0.001");
  await page.waitForFunction(() => /scaled ×1000 into the target's unit/.test(document.getElementById("source-info").textContent), null, { timeout: TIMEOUT });
  assert.equal((await page.textContent("#result")).trim(), "", "the old result is cleared");
  ({ result, error } = await alignAndWait());
  assert.equal(error, "", `unexpected #error: ${error}`);
  const truthMm = Float64Array.from(TRUTH, (v, i) => (i >= 12 && i < 15 ? v * 1000 : v));
  const e = errorsAgainstTruth(result, truthMm);
  console.log(`metres onto millimetres: rotation error ${e.rotationDeg.toFixed(3)} deg, translation error ${e.translation.toFixed(1)} mm`);
  assert.ok(e.rotationDeg < 5, `rotation error ${e.rotationDeg} deg`);
  assert.ok(e.translation < 250, `translation error ${e.translation} mm`);
  assert.ok(!result.warnings.some((w) => /differ in size/.test(w)), JSON.stringify(result.warnings));
  // "Source on target: all" passes sourceOverlap 1: the street scans are two partial views (84% of
  // the source lies near the target), so the answer is flagged, its share said.
  await page.selectOption("#source-overlap", "1");
  try {
    ({ result, error } = await alignAndWait());
    assert.equal(error, "", `unexpected #error: ${error}`);
    assert.ok(result.warnings.some((w) => /of the source lies within .* sourceOverlap says 100%/.test(w)), JSON.stringify(result.warnings));
    assert.ok(result.confidence <= 0.25, String(result.confidence));
  } finally {
    await page.selectOption("#source-overlap", "");
  }
  // Back to the same unit: the source as read again.
  await page.selectOption("#target-unit", "1");
  await page.waitForFunction(() => !/scaled/.test(document.getElementById("source-info").textContent), null, { timeout: TIMEOUT });
});

test("a mesh file is read as points over its surface", { timeout: TIMEOUT * 2 }, async () => {
  // A CAD part's STL (398 vertices, on its edges): the page reads 200,000 points over its faces.
  await page.setInputFiles("#target-file", join(ROOT, "fixtures", "formats", "angle_block_binary_solid.stl"));
  await page.waitForFunction(() => /angle_block/.test(document.getElementById("target-info").textContent), null, { timeout: TIMEOUT });
  await page.waitForFunction(() => /points/.test(document.getElementById("target-info").textContent), null, { timeout: TIMEOUT });
  assert.match(await page.textContent("#target-info"), /200,000 points/);
});

test("a georeferenced LAZ survey aligned onto itself moved, in map-grid coordinates, as the package does it", { timeout: TIMEOUT * 2 }, async () => {
  // The source: fixtures/formats/1_4_w_evlr.laz as is (LAS 1.4, layered LAZ, 1,000 points near
  // (1.69e6, 1.82e6, 5.6e3), where float32 steps are 0.125). The target: its points moved by 12
  // degrees about the vertical through the survey's centre plus (4, -3, 0.5), written as a PLY of
  // doubles. The page keeps each scan as float32 offsets from a float64 origin, so its answer must
  // be the package's own on the same files in Node, and its download the source moved in f64 (the
  // LAZ file as LAZ, stored with its own scales).
  const arps = await import(pathToFileURL(join(ROOT, "pkg", "node", "index.mjs")).href);
  const laz = join(ROOT, "fixtures", "formats", "1_4_w_evlr.laz");
  const cloud = arps.readPointCloud(readFileSync(laz), "1_4_w_evlr.laz");
  const n = cloud.points.length / 3;
  const p = (i, k) => cloud.origin[k] + cloud.points[3 * i + k];
  const centre = [0, 1, 2].map((k) => { let s = 0; for (let i = 0; i < n; i++) s += p(i, k); return s / n; });
  const a = (12 * Math.PI) / 180;
  const move = (x, y, z) => [
    centre[0] + Math.cos(a) * (x - centre[0]) - Math.sin(a) * (y - centre[1]) + 4,
    centre[1] + Math.sin(a) * (x - centre[0]) + Math.cos(a) * (y - centre[1]) - 3,
    z + 0.5,
  ];
  const header = `ply\nformat binary_little_endian 1.0\nelement vertex ${n}\nproperty double x\nproperty double y\nproperty double z\nend_header\n`;
  const body = new Float64Array(3 * n);
  for (let i = 0; i < n; i++) body.set(move(p(i, 0), p(i, 1), p(i, 2)), 3 * i);
  const moved = Buffer.concat([Buffer.from(header), Buffer.from(body.buffer)]);
  writeFileSync(join(dir, "survey-moved.ply"), moved);
  await page.setInputFiles("#source-file", laz);
  await page.waitForFunction(() => /1_4_w_evlr\.laz · 1,000 points/.test(document.getElementById("source-info").textContent), null, { timeout: TIMEOUT });
  // the page says where a survey lies
  assert.match(await page.textContent("#source-info"), /about \(1,69\d,\d{3}(\.\d)?, 1,8\d{2},\d{3}(\.\d)?, 5,\d{3}(\.\d)?\)/);
  await page.setInputFiles("#target-file", join(dir, "survey-moved.ply"));
  await page.waitForFunction(() => /survey-moved\.ply · 1,000 points/.test(document.getElementById("target-info").textContent), null, { timeout: TIMEOUT });
  const { result, error } = await alignAndWait();
  assert.equal(error, "", `unexpected #error: ${error}`);

  // The package in Node, on the same files with the page's options, in f64: the same answer.
  const registrar = arps.Registrar.withDefaultModel();
  const target = arps.readPointCloud(moved, "survey-moved.ply");
  const node = registrar.register(cloud, target, { icp: "plane", search: "adaptive", seed: 0 });
  registrar.free();
  const m = result.T_target_source; // row-major
  let apart = 0;
  for (let r = 0; r < 4; r++) for (let c = 0; c < 4; c++) apart = Math.max(apart, Math.abs(m[r][c] - node.T_target_source[c * 4 + r]));
  assert.ok(apart < 1e-6, `the page's answer is ${apart} from the package's`);

  // where the answer puts the survey's centre, against where the motion does
  const at = [0, 1, 2].map((r) => m[r][0] * centre[0] + m[r][1] * centre[1] + m[r][2] * centre[2] + m[r][3]);
  const want = move(...centre);
  const off = Math.hypot(at[0] - want[0], at[1] - want[1], at[2] - want[2]);
  console.log(
    `LAZ survey: the page's answer ${apart.toExponential(1)} from the package's in Node; the centre off by ${off.toFixed(4)}, ` +
      `rotation ${result.rotationDeg.toFixed(2)} deg (12 applied), confidence ${result.confidence.toFixed(3)}`,
  );
  // 1,000 points over a strip about 500 long: a few units apart, so ICP's last distance, and what
  // a slide along the strip costs, are a few tenths
  assert.ok(off < 1.0, `the survey's centre off by ${off}`);
  assert.ok(Math.abs(result.rotationDeg - 12) < 0.5, `page says ${result.rotationDeg} deg`);
  // how far the source's centre (of its box) moves: a few units, where the translation is 1e5
  const lo = [0, 1, 2].map((k) => { let v = Infinity; for (let i = 0; i < n; i++) v = Math.min(v, p(i, k)); return v; });
  const hi = [0, 1, 2].map((k) => { let v = -Infinity; for (let i = 0; i < n; i++) v = Math.max(v, p(i, k)); return v; });
  const box = [0, 1, 2].map((k) => (lo[k] + hi[k]) / 2);
  const shift = move(...box).map((v, k) => v - box[k]);
  const shiftOff = Math.hypot(...result.sourceCentreMoves.map((v, k) => v - shift[k]));
  assert.ok(shiftOff < 1.0, `the page says the centre moves by ${result.sourceCentreMoves}, the motion by ${shift}`);
  assert.match(await page.textContent("#figures"), /Centre moves\(-?[\d.]+, -?[\d.]+, -?[\d.]+\) · [\d.]+ units/);

  // The view frames the survey (drawn as offsets from the target's origin) and shows the aligned
  // source on the target.
  await page.click("#fit");
  await settle();
  mkdirSync(OUT, { recursive: true });
  await page.screenshot({ path: join(OUT, "survey.png") });
  const green = await pixelsNear([0x4a, 0xde, 0x80]);
  const orange = await pixelsNear([0xf9, 0x73, 0x16]);
  console.log(`LAZ survey view: aligned (green) pixels ${green}, source (orange) ${orange}`);
  assert.ok(green > 1000 && orange === 0, `aligned (green) pixels ${green}, source (orange) ${orange}`);

  // The download (the engine's transformFile): the LAZ survey comes back as LAZ, moved by the
  // answer, its points stored with the file's own scales and compressed again.
  const [download] = await Promise.all([page.waitForEvent("download"), page.click("#download-ply")]);
  assert.equal(download.suggestedFilename(), "1_4_w_evlr-aligned.laz");
  const file = join(dir, "survey-aligned.laz");
  await download.saveAs(file);
  const saved = readFileSync(file);
  assert.equal(saved.subarray(0, 4).toString("latin1"), "LASF");
  assert.equal(saved[104] & 0x80, 0x80, "marked compressed");
  assert.ok(saved.length < readFileSync(laz).length * 1.5, `${saved.length} bytes, the LAZ file ${readFileSync(laz).length}`);
  const scale = [0, 1, 2].map((k) => saved.readDoubleLE(131 + 8 * k));
  const back = arps.readPointCloud(saved, "survey-aligned.laz");
  assert.equal(back.points.length / 3, n);
  let worst = 0;
  for (let i = 0; i < n; i++) {
    for (let r = 0; r < 3; r++) {
      const want = m[r][0] * p(i, 0) + m[r][1] * p(i, 1) + m[r][2] * p(i, 2) + m[r][3];
      const got = back.origin[r] + back.points[3 * i + r];
      worst = Math.max(worst, Math.abs(got - want) - scale[r] / 2);
    }
  }
  // stored to the file's own scale (about 1e-6 here): within half a step of the answer applied
  // in f64 to the points as read (float32 offsets beside a float64 origin, on both sides: microns)
  assert.ok(worst < 1e-4, `the aligned survey's points are up to ${worst} (beyond half a step) from the answer applied in f64`);
});

test("a LAS survey is downloaded as LAS, moved as it is", { timeout: TIMEOUT * 2 }, async () => {
  // fixtures/formats/simple.las (LAS 1.2 format 3: colour, GPS time) onto the moved survey of the
  // test before: the download is the LAS file itself, moved by the answer (the engine's
  // transformFile), its attributes kept
  const las = join(ROOT, "fixtures", "formats", "simple.las");
  await page.setInputFiles("#source-file", las);
  await page.waitForFunction(() => /simple\.las · 1,065 points/.test(document.getElementById("source-info").textContent), null, { timeout: TIMEOUT });
  await page.setInputFiles("#target-file", las);
  await page.waitForFunction(() => /simple\.las · 1,065 points/.test(document.getElementById("target-info").textContent), null, { timeout: TIMEOUT });
  const { result, error } = await alignAndWait();
  assert.equal(error, "", `unexpected #error: ${error}`);
  const [download] = await Promise.all([page.waitForEvent("download"), page.click("#download-ply")]);
  assert.equal(download.suggestedFilename(), "simple-aligned.las");
  const file = join(dir, "simple-aligned.las");
  await download.saveAs(file);
  const [before, after] = [readFileSync(las), readFileSync(file)];
  assert.equal(after.length, before.length);
  assert.equal(after.subarray(0, 4).toString("latin1"), "LASF");
  const offset = before.readUInt32LE(96);
  assert.ok(after.subarray(offset + 12, offset + 34).equals(before.subarray(offset + 12, offset + 34)), "the first record's attributes");
  // its first point is where the answer puts it (to the file's 0.01 scale)
  const m = result.T_target_source; // row-major
  const p = [0, 1, 2].map((k) => before.readInt32LE(offset + 4 * k) * before.readDoubleLE(131 + 8 * k) + before.readDoubleLE(155 + 8 * k));
  const q = [0, 1, 2].map((k) => after.readInt32LE(offset + 4 * k) * after.readDoubleLE(131 + 8 * k) + after.readDoubleLE(155 + 8 * k));
  const want = [0, 1, 2].map((r) => m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2] + m[r][3]);
  assert.ok(Math.hypot(...q.map((v, k) => v - want[k])) < 0.01, `first point ${q} vs ${want}`);
});

test("a PCD scan is downloaded as PCD, moved as it is", { timeout: TIMEOUT * 2 }, async () => {
  // fixtures/formats/velodyne_2000_binary.pcd (x y z intensity, float) onto itself: the download
  // is the PCD file itself, its header and intensities kept, its points moved by the answer
  const pcd = join(ROOT, "fixtures", "formats", "velodyne_2000_binary.pcd");
  for (const which of ["source", "target"]) {
    await page.setInputFiles(`#${which}-file`, pcd);
    await page.waitForFunction((id) => /velodyne_2000_binary\.pcd · 2,000 points/.test(document.getElementById(id).textContent), `${which}-info`, { timeout: TIMEOUT });
  }
  const { result, error } = await alignAndWait();
  assert.equal(error, "", `unexpected #error: ${error}`);
  const [download] = await Promise.all([page.waitForEvent("download"), page.click("#download-ply")]);
  assert.equal(download.suggestedFilename(), "velodyne_2000_binary-aligned.pcd");
  const file = join(dir, "velodyne-aligned.pcd");
  await download.saveAs(file);
  const [before, after] = [readFileSync(pcd), readFileSync(file)];
  const body = before.indexOf("DATA binary\n") + 12;
  assert.equal(after.length, before.length);
  assert.ok(after.subarray(0, body).equals(before.subarray(0, body)), "the header");
  const m = result.T_target_source; // row-major
  let worst = 0;
  for (let i = 0; i < 2000; i++) {
    const at = body + 16 * i;
    assert.equal(after.readFloatLE(at + 12), before.readFloatLE(at + 12), `intensity of point ${i}`);
    const p = [0, 1, 2].map((k) => before.readFloatLE(at + 4 * k));
    const want = [0, 1, 2].map((r) => m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2] + m[r][3]);
    worst = Math.max(worst, ...[0, 1, 2].map((k) => Math.abs(after.readFloatLE(at + 4 * k) - want[k])));
  }
  assert.ok(worst < 1e-5, `the points are up to ${worst} from the answer applied`);
});

test("an E57 file of several scans offers them: all, or one read alone; saved as E57, whole or that scan", { timeout: TIMEOUT * 2 }, async () => {
  // fixtures/formats/velodyne_two_scans.e57: two scans of 1,000 points, each placed by its pose
  const e57 = join(ROOT, "fixtures", "formats", "velodyne_two_scans.e57");
  assert.ok(await page.isHidden("#source-scan-field"), "no scan choice before an E57 file");
  await page.setInputFiles("#source-file", e57);
  await page.waitForFunction(() => /velodyne_two_scans\.e57 · 2,000 points/.test(document.getElementById("source-info").textContent), null, { timeout: TIMEOUT });
  assert.ok(await page.isVisible("#source-scan-field"));
  const options = await page.$$eval("#source-scan option", (os) => os.map((o) => [o.value, o.textContent]));
  assert.deepEqual(options, [["", "all 2 scans"], ["0", "1: scan 1 (1,000 points)"], ["1", "2: scan 2 (1,000 points)"]]);
  await page.selectOption("#source-scan", "1");
  await page.waitForFunction(() => /velodyne_two_scans\.e57, scan 2 · 1,000 points/.test(document.getElementById("source-info").textContent), null, { timeout: TIMEOUT });
  assert.equal(await page.inputValue("#source-scan"), "1", "the choice stays");
  // aligned alone onto the whole file: it is the file's second half, so it lands where it is
  await page.setInputFiles("#target-file", e57);
  await page.waitForFunction(() => /velodyne_two_scans\.e57 · 2,000 points/.test(document.getElementById("target-info").textContent), null, { timeout: TIMEOUT });
  const { result, error } = await alignAndWait();
  assert.equal(error, "", `unexpected #error: ${error}`);
  assert.ok(result.rotationDeg < 1, `scan 2 onto the file turned by ${result.rotationDeg} deg`);
  // one scan is saved as an E57 file of that scan: its points where the answer puts them (scan 2
  // onto the file: about where it was)
  let [download] = await Promise.all([page.waitForEvent("download"), page.click("#download-ply")]);
  assert.equal(download.suggestedFilename(), "velodyne_two_scans-scan2-aligned.e57");
  const one = join(dir, "scan2-aligned.e57");
  await download.saveAs(one);
  const arps = await import(pathToFileURL(join(ROOT, "pkg", "node", "index.mjs")).href);
  const saved = readFileSync(one);
  assert.deepEqual(arps.listScans(saved, "one.e57"), [{ name: "scan 2", records: 1000 }]);
  assert.ok(saved.length < readFileSync(e57).length, `${saved.length} bytes, the file ${readFileSync(e57).length}`);
  const centroid = (c) => [0, 1, 2].map((k) => c.origin[k] + c.points.reduce((s, v, i) => (i % 3 === k ? s + v : s), 0) / (c.points.length / 3));
  const [was, now] = [centroid(arps.readPointCloud(readFileSync(e57), "a.e57", { scan: 1 })), centroid(arps.readPointCloud(saved, "a.e57"))];
  assert.ok(Math.hypot(...was.map((v, k) => v - now[k])) < 0.5, `scan 2's centre moved from ${was} to ${now}`);
  // back to all scans: aligned onto the file, the file is saved as E57 with its scans' poses
  // moved (its points' pages kept byte for byte)
  await page.selectOption("#source-scan", "");
  await page.waitForFunction(() => /velodyne_two_scans\.e57 · 2,000 points/.test(document.getElementById("source-info").textContent), null, { timeout: TIMEOUT });
  const again = await alignAndWait();
  assert.equal(again.error, "", `unexpected #error: ${again.error}`);
  [download] = await Promise.all([page.waitForEvent("download"), page.click("#download-ply")]);
  assert.equal(download.suggestedFilename(), "velodyne_two_scans-aligned.e57");
  const file = join(dir, "two-aligned.e57");
  await download.saveAs(file);
  const [before, after] = [readFileSync(e57), readFileSync(file)];
  assert.ok(after.length > before.length && after.subarray(1024, before.length).equals(before.subarray(1024)), "the points' pages kept");
  await page.setInputFiles("#source-file", join(ROOT, "fixtures", "formats", "velodyne_2000_binary.pcd"));
  await page.waitForFunction(() => /velodyne_2000_binary\.pcd · 2,000 points/.test(document.getElementById("source-info").textContent), null, { timeout: TIMEOUT });
  assert.ok(await page.isHidden("#source-scan-field"));
});

test("a 1M-point pair: loaded, fitted and aligned without blocking the main thread", { timeout: TIMEOUT * 3 }, async () => {
  const infoDone = (which) =>
    page.waitForFunction((id) => /[\d,]+ points( ·|$)/.test(document.getElementById(id).textContent), `${which}-info`, { timeout: TIMEOUT });
  const load = await measured(async () => {
    await page.setInputFiles("#source-file", join(dir, "big-source.ply"));
    await infoDone("source");
    await page.setInputFiles("#target-file", join(dir, "big-target.ply"));
    await infoDone("target");
  });
  assert.match(await page.textContent("#source-info"), /1,000,000 points · [\d,]+ drawn/);
  assert.match(await page.textContent("#target-info"), /1,000,000 points · [\d,]+ drawn/);
  const fit = await measured(() => page.click("#fit"));
  let result = null;
  const align = await measured(async () => {
    let error;
    ({ result, error } = await alignAndWait());
    assert.equal(error, "", `unexpected #error: ${error}`);
  });
  const e = errorsAgainstTruth(result);
  console.log(
    `1M vs 1M: load ${(load.ms / 1000).toFixed(1)} s (long tasks ${JSON.stringify(load.tasks)} ms), fit (long tasks ${JSON.stringify(fit.tasks)}), ` +
      `align ${(align.ms / 1000).toFixed(1)} s, engine ${result.timings.totalMs.toFixed(0)} ms (long tasks ${JSON.stringify(align.tasks)}); ` +
      `rotation error ${e.rotationDeg.toFixed(3)} deg, translation error ${e.translation.toFixed(4)} m, fitness ${result.fitness.toFixed(3)}`,
  );
  assert.ok(e.rotationDeg < 2, `rotation error ${e.rotationDeg} deg`);
  assert.ok(e.translation < 0.25, `translation error ${e.translation} m`);
  for (const [phase, m] of Object.entries({ load, fit, align })) {
    assert.ok(m.longest < LONGEST_TASK_MS, `${phase}: the main thread was blocked for ${m.longest.toFixed(0)} ms (long tasks ${JSON.stringify(m.tasks)})`);
  }

  // Desktop: the result and its buttons are on screen without scrolling.
  mkdirSync(OUT, { recursive: true });
  await settle();
  await page.screenshot({ path: join(OUT, "big-1400x860.png") });
  // The view shows the aligned source (green), not the source where it was (orange).
  const green = await pixelsNear([0x4a, 0xde, 0x80]);
  const orange = await pixelsNear([0xf9, 0x73, 0x16]);
  assert.ok(green > 2000 && orange < green / 10, `aligned (green) pixels ${green}, source (orange) ${orange}`);
  for (const id of ["#verdict", "#matrix", "#copy-matrix", "#download-ply"]) {
    assert.ok(inViewport(await page.locator(id).boundingBox(), DESKTOP), `${id} is not inside the 1400x860 viewport`);
  }
  // Phone: one column; nothing wider than the screen; the result scrolls into view whole-width.
  await page.setViewportSize(PHONE);
  try {
    await page.locator("#results").scrollIntoViewIfNeeded();
    await settle();
    await page.screenshot({ path: join(OUT, "big-390x844.png") });
    assert.ok((await page.evaluate(() => document.documentElement.scrollWidth)) <= PHONE.width, "the page scrolls sideways at 390 px");
    for (const id of ["#verdict", "#copy-matrix", "#download-ply"]) {
      const box = await page.locator(id).boundingBox();
      assert.ok(box.x >= 0 && box.x + box.width <= PHONE.width, `${id} is cut off at 390 px: ${JSON.stringify(box)}`);
    }
    assert.ok(inViewport(await page.locator("#verdict").boundingBox(), PHONE), "#verdict not on screen at 390x844");
  } finally {
    await page.setViewportSize(DESKTOP);
  }
});

test("no uncaught errors on the page", () => {
  const errors = consoleLines.filter((l) => l.startsWith("pageerror:") || l.startsWith("console.error:"));
  assert.deepEqual(errors, []);
});
