// End-to-end test of the demo page (www/) in Debian's Chromium, headless, through playwright-core.
// Needs the built package (scripts/build-pkg.sh) and the npm dev dependencies; run it with
// scripts/test-e2e.sh. The screenshot goes to $ARPS_E2E_OUT (default target/e2e/demo.png).
//
// The known-transform pair: two half-space crops (85% each) of the committed Velodyne fixture
// (fixtures/scans/velodyne-small.ply, MIT), the target moved by 15 degrees about a near-vertical
// axis plus (1.0, -0.6, 0.2) m. A modest motion on purpose: the embedded default model may still be
// an untrained placeholder, and ICP alone recovers this one.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { mkdirSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from "node:fs";
import { tmpdir } from "node:os";
import { dirname, join, resolve } from "node:path";
import { fileURLToPath } from "node:url";
import { chromium } from "playwright-core";
import { PNG } from "pngjs";
import { serve } from "../../scripts/serve.mjs";
import { confidenceWords, crop, invertRigid, multiply, rigid, rotationAngleDeg, transformPoints, writePly } from "../../www/lib.js";

const ROOT = resolve(dirname(fileURLToPath(import.meta.url)), "../..");
const CHROMIUM = process.env.ARPS_CHROMIUM ?? "/usr/bin/chromium";
const OUT = resolve(ROOT, process.env.ARPS_E2E_OUT ?? "target/e2e");
const TIMEOUT = 120_000;

const TRUTH = rigid([0.1, 0.15, 1], 15, [1.0, -0.6, 0.2]);

let server;
let url;
let browser;
let page;
let dir;
const consoleLines = [];

function readFloatPly(path) {
  const buf = readFileSync(path);
  const head = buf.indexOf("end_header\n") + "end_header\n".length;
  const header = buf.subarray(0, head).toString("latin1");
  assert.match(header, /format binary_little_endian 1\.0/);
  const n = Number(header.match(/element vertex (\d+)/)[1]);
  const body = buf.subarray(head, head + n * 12);
  return new Float32Array(body.buffer.slice(body.byteOffset, body.byteOffset + body.length));
}

before(async () => {
  dir = mkdtempSync(join(tmpdir(), "arps-e2e-"));
  const scan = readFloatPly(join(ROOT, "fixtures/scans/velodyne-small.ply"));
  const source = crop(scan, [1, 0.2, 0], 0.85).points;
  const target = transformPoints(crop(scan, [-1, 0.3, 0], 0.85).points, TRUTH);
  writeFileSync(join(dir, "source.ply"), writePly(source, "e2e source"));
  writeFileSync(join(dir, "target.ply"), writePly(target, "e2e target: source frame moved by a known transform"));
  writeFileSync(join(dir, "broken.ply"), "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\nnot numbers\n");

  ({ server, url } = await serve({ port: 0 }));
  // A fresh profile (--user-data-dir) in the temp dir, through playwright's persistent context.
  browser = await chromium.launchPersistentContext(join(dir, "profile"), {
    executablePath: CHROMIUM,
    viewport: { width: 1280, height: 800 },
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

function errorsAgainstTruth(result) {
  const rows = result.T_target_source;
  assert.equal(rows.length, 4);
  const m = new Float64Array(16);
  for (let r = 0; r < 4; r++) for (let c = 0; c < 4; c++) m[c * 4 + r] = rows[r][c];
  const err = multiply(invertRigid(TRUTH), m);
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
  assert.equal(verdict, confidenceWords(result.confidence).words);
  assert.match(verdict, /^(likely right|uncertain|likely wrong) \(confidence [01]\.\d\d\)$/);
  assert.match(await page.textContent("#figures-help"), /RMSE.*in the scans' units/);
});

test("confidence in words: thresholds at 0.8 and 0.5", () => {
  assert.deepEqual(confidenceWords(0.93), { words: "likely right (confidence 0.93)", level: "right" });
  assert.deepEqual(confidenceWords(0.8), { words: "likely right (confidence 0.80)", level: "right" });
  assert.deepEqual(confidenceWords(0.62), { words: "uncertain (confidence 0.62)", level: "uncertain" });
  assert.deepEqual(confidenceWords(0.12), { words: "likely wrong (confidence 0.12)", level: "wrong" });
  assert.equal(confidenceWords(undefined).level, "uncertain");
});

test("download the aligned source as PLY; copy the matrix as JSON", async () => {
  const result = JSON.parse(await page.textContent("#result"));
  const [download] = await Promise.all([page.waitForEvent("download"), page.click("#download-ply")]);
  assert.equal(download.suggestedFilename(), "source-aligned.ply");
  const file = join(dir, "aligned.ply");
  await download.saveAs(file);
  const aligned = readFloatPly(file);
  const source = crop(readFloatPly(join(ROOT, "fixtures/scans/velodyne-small.ply")), [1, 0.2, 0], 0.85).points;
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
  await page.screenshot({ path: join(OUT, "demo.png") });
  const png = PNG.sync.read(await page.locator("#canvas").screenshot());
  const bg = [png.data[0], png.data[1], png.data[2]]; // a corner: the background
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
  await page.setInputFiles("#source-file", join(dir, "broken.ply"));
  await page.waitForFunction(() => document.getElementById("error").textContent.trim(), null, { timeout: TIMEOUT });
  const message = (await page.textContent("#error")).trim();
  console.log(`#error: ${message}`);
  assert.match(message, /broken\.ply/);
  assert.equal((await page.textContent("#result")).trim(), "");
  assert.ok(await page.isDisabled("#align"), "Align stays disabled without a source");

  // Still usable: a good file again, and Align works.
  await uploadPair();
  assert.equal((await page.textContent("#error")).trim(), "");
  const { result, error } = await alignAndWait();
  assert.equal(error, "");
  assert.ok(errorsAgainstTruth(result).rotationDeg < 5);
});

test("too few points: the engine's error is shown", { timeout: TIMEOUT * 2 }, async () => {
  writeFileSync(join(dir, "tiny.xyz"), "0 0 0\n1 0 0\n0 1 0\n");
  await page.setInputFiles("#source-file", join(dir, "tiny.xyz"));
  await page.waitForFunction(() => /3 points/.test(document.getElementById("source-info").textContent), null, { timeout: TIMEOUT });
  const { result, error } = await alignAndWait();
  console.log(`#error: ${error}`);
  assert.equal(result, null);
  assert.ok(error.length > 0);
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

test("no uncaught errors on the page", () => {
  const errors = consoleLines.filter((l) => l.startsWith("pageerror:") || l.startsWith("console.error:"));
  assert.deepEqual(errors, []);
});
