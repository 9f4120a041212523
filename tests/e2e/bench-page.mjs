// Main-thread blocking of the demo page on a 1M-point pair, for BENCHMARK.md (not a test):
//   node tests/e2e/bench-page.mjs [--runs 3] [--root DIR] [--points 1000000]
// DIR: a directory laid out like the repository (www/, pkg/, node_modules/, scripts/serve.mjs),
// default this checkout; point it at an old copy of www/ to compare. Per run (a fresh page in
// headless Chromium with software WebGL, 1400x860), for loading the two files, "Fit view" and
// aligning: the wall time, the longest main-thread long task, and their total (ms); then medians.
// The pair is that of tests/e2e/demo.test.mjs (the Velodyne fixture's crops, densified).
import { mkdtempSync, rmSync, writeFileSync } from "node:fs";
import { tmpdir } from "node:os";
import { dirname, join, resolve } from "node:path";
import { fileURLToPath, pathToFileURL } from "node:url";
import { parseArgs } from "node:util";
import { chromium } from "playwright-core";
import { streetPair } from "./street-pair.mjs";

const HERE = resolve(dirname(fileURLToPath(import.meta.url)), "../..");
const { values: args } = parseArgs({ options: { runs: { type: "string", default: "3" }, root: { type: "string", default: HERE }, points: { type: "string", default: "1000000" } } });
const N = Number(args.points);

const dir = mkdtempSync(join(tmpdir(), "arps-bench-page-"));
const pair = streetPair(N);
writeFileSync(join(dir, "source.ply"), pair.source);
writeFileSync(join(dir, "target.ply"), pair.target);

const { serve } = await import(pathToFileURL(join(resolve(args.root), "scripts/serve.mjs")).href);
const { server, url } = await serve({ port: 0 });
const browser = await chromium.launch({
  executablePath: process.env.ARPS_CHROMIUM ?? "/usr/bin/chromium",
  headless: true,
  args: ["--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader"],
});
const rows = [];
try {
  for (let run = 0; run < Number(args.runs); run++) {
    const page = await browser.newPage({ viewport: { width: 1400, height: 860 } });
    await page.addInitScript(() => {
      window.__lt = [];
      new PerformanceObserver((l) => {
        for (const e of l.getEntries()) window.__lt.push([e.startTime, e.duration]);
      }).observe({ type: "longtask", buffered: true });
    });
    await page.goto(url);
    await page.waitForFunction(() => /engine ready/.test(document.getElementById("engine-status").textContent), null, { timeout: 120_000 });
    const drawn = () =>
      page.waitForFunction(() => {
        const d = document.getElementById("canvas").dataset;
        return d.sent === undefined || d.sent === d.drawn; // pages without the hook: no wait
      }, null, { timeout: 120_000 });
    const phase = async (fn) => {
      const t0 = await page.evaluate(() => performance.now());
      const wall = performance.now();
      await fn();
      const ms = performance.now() - wall;
      await page.waitForTimeout(1500); // late tasks (the old page drew on the main thread)
      const tasks = await page.evaluate((t) => window.__lt.filter(([s]) => s >= t).map(([, d]) => Math.round(d)), t0);
      return { ms: Math.round(ms), longest: Math.max(0, ...tasks), total: tasks.reduce((a, b) => a + b, 0) };
    };
    const info = (id) => page.waitForFunction((id) => /[\d,]+ points( ·|$)/.test(document.getElementById(id).textContent), id, { timeout: 120_000 });
    const load = await phase(async () => {
      await page.setInputFiles("#source-file", join(dir, "source.ply"));
      await info("source-info");
      await page.setInputFiles("#target-file", join(dir, "target.ply"));
      await info("target-info");
      await drawn();
    });
    const fit = await phase(() => page.click("#fit"));
    const align = await phase(async () => {
      await page.click("#align");
      await page.waitForFunction(() => document.getElementById("result").textContent.trim() || document.getElementById("error").textContent.trim(), null, { timeout: 120_000 });
      await drawn();
    });
    rows.push({ load, fit, align });
    console.log(`run ${run + 1}: ${JSON.stringify({ load, fit, align })}`);
    await page.close();
  }
} finally {
  await browser.close();
  server.close();
  rmSync(dir, { recursive: true, force: true });
}
const median = (a) => [...a].sort((x, y) => x - y)[Math.floor(a.length / 2)];
for (const p of ["load", "fit", "align"]) {
  const m = (k) => median(rows.map((r) => r[p][k]));
  console.log(`${p}: median wall ${m("ms")} ms, longest long task ${m("longest")} ms, total blocked ${m("total")} ms`);
}
