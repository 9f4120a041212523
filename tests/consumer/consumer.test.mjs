// Consumer test of the packed npm package (scripts/test-consumer.sh runs it): `npm pack` of pkg/,
// the tarball installed into a fresh app (a copy of tests/consumer/template/ in a temp dir), then
// what users do with it, through the package's public entry points only:
//   - the tarball's content (no tests, source maps, repo sources or data; licences, changelog,
//     examples, every file package.json points at) and `npm publish --dry-run` without warnings;
//   - TypeScript against the installed package: ESM with moduleResolution "bundler" and
//     "NodeNext", CommonJS with esModuleInterop ("node10" and "Node16" resolution); the value
//     exports the declarations give each setup equal the runtime's (no internal exports), and no
//     other file of the package can be imported;
//   - the compiled Node apps (ESM: main thread and worker client; CommonJS: `import init from
//     "arps"`) and the package's examples/node-register.mjs align the fixture pair
//     (fixtures/wasm, known transform) and report misuse with clear errors;
//   - the package's examples/browser built with Vite and, separately, served as plain files with
//     its import map, each aligning the pair in headless Chromium through the worker client.
// Nothing here lists the package's files: the checks read package.json and `npm pack --json`.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { execFile } from "node:child_process";
import { cpSync, mkdtempSync, readFileSync, readdirSync, rmSync, symlinkSync, writeFileSync } from "node:fs";
import { tmpdir } from "node:os";
import { dirname, join, resolve } from "node:path";
import { fileURLToPath } from "node:url";
import { promisify } from "node:util";
import ts from "typescript";
import { build, preview } from "vite";
import { chromium } from "playwright-core";

const run = promisify(execFile);
const ROOT = resolve(dirname(fileURLToPath(import.meta.url)), "../..");
const PKG = join(ROOT, "pkg");
const FIXTURES = join(ROOT, "fixtures/wasm");
const SOURCE = join(FIXTURES, "source.ply");
const TARGET = join(FIXTURES, "target.ply");
const CHROMIUM = process.env.ARPS_CHROMIUM ?? "/usr/bin/chromium";
/** T_target_source of the fixture pair, row-major rows. */
const TRUTH = JSON.parse(readFileSync(join(FIXTURES, "pair.json"), "utf8")).T_target_source;
const MAX_ROTATION_DEG = 0.5;
const MAX_TRANSLATION = 0.01; // the pair's translation is (0.3, -0.2, 0.15)

let dir; // the temp dir: the tarball, the app, an empty npm user config
let app; // the fresh app with the tarball installed
let env; // npm isolated from the user's npm config (its warnings are not the package's)
let packed; // npm pack --json's entry: { filename, files: [{ path, size }], ... }
let manifest; // the packed package.json

before(async () => {
  dir = mkdtempSync(join(tmpdir(), "arps-consumer-"));
  writeFileSync(join(dir, "npmrc"), "");
  env = {
    ...process.env,
    npm_config_userconfig: join(dir, "npmrc"),
    npm_config_update_notifier: "false",
    npm_config_fund: "false",
    npm_config_audit: "false",
  };
  const { stdout } = await run("npm", ["pack", "--json", "--pack-destination", dir], { cwd: PKG, env });
  [packed] = JSON.parse(stdout);
  app = join(dir, "app");
  cpSync(join(ROOT, "tests/consumer/template"), app, { recursive: true });
  await run("npm", ["install", "--offline", "--no-package-lock", join(dir, packed.filename)], { cwd: app, env });
  manifest = JSON.parse(readFileSync(join(app, "node_modules/arps/package.json"), "utf8"));
  // The apps' Node types come from the repo's pinned @types/node (no registry access here).
  symlinkSync(join(ROOT, "node_modules/@types"), join(app, "node_modules/@types"), "dir");
});

after(() => {
  if (dir && !process.env.ARPS_CONSUMER_KEEP) rmSync(dir, { recursive: true, force: true });
  else if (dir) console.log(`kept ${dir}`);
});

/** Every file path that package.json points at (main, module, types, exports targets). */
function pointedAt(p) {
  const out = new Set();
  const walk = (v) => {
    if (typeof v === "string") out.add(v.replace(/^\.\//, ""));
    else if (v && typeof v === "object") Object.values(v).forEach(walk);
  };
  walk([p.main, p.module, p.types, p.exports]);
  return out;
}

test("the tarball holds the package, its licences, changelog and examples, and nothing of the repo", () => {
  const files = packed.files.map((f) => f.path);
  for (const f of files) {
    assert.doesNotMatch(f, /(^|\/)(tests?|__tests__|spec|fixtures)\//i, `a test folder in the tarball: ${f}`);
    assert.doesNotMatch(f, /\.(test|spec)\.[cm]?[jt]s$/i, `a test file in the tarball: ${f}`);
    assert.doesNotMatch(f, /\.map$/i, `a source map in the tarball: ${f}`);
    assert.doesNotMatch(f, /\.(ply|pcd|xyz|pts|csv|obj|off|stl|las|laz|e57|npy|npz|gz|zip|tgz|tar)$/i, `data in the tarball: ${f}`);
    assert.doesNotMatch(f, /\.rs$|(^|\/)Cargo\.(toml|lock)$|(^|\/)\./, `repository sources in the tarball: ${f}`);
    assert.ok(!/\.[cm]?ts$/.test(f) || /\.d\.[cm]?ts$/.test(f), `TypeScript sources in the tarball: ${f}`);
  }
  for (const f of ["package.json", "README.md", "CHANGELOG.md", "LICENSE-MIT", "LICENSE-APACHE"]) {
    assert.ok(files.includes(f), `${f} is missing from the tarball`);
  }
  assert.ok(files.some((f) => f.startsWith("examples/")), "no examples/ in the tarball");
  for (const f of pointedAt(manifest)) assert.ok(files.includes(f), `package.json points at ${f}, which is not in the tarball`);
  assert.match(readFileSync(join(app, "node_modules/arps/LICENSE-APACHE"), "utf8"), /Apache License\s+Version 2\.0, January 2004/);
  assert.match(readFileSync(join(app, "node_modules/arps/LICENSE-MIT"), "utf8"), /^MIT License/);
  assert.match(readFileSync(join(app, "node_modules/arps/CHANGELOG.md"), "utf8"), new RegExp(`## \\[${manifest.version.replace(/\./g, "\\.")}\\]`));
  assert.equal(manifest.license, "MIT OR Apache-2.0");
  assert.match(manifest.repository?.url ?? "", /^git\+https:\/\/github\.com\/[^/]+\/[^/]+\.git$/);
  assert.match(manifest.homepage ?? "", /^https:\/\/github\.com\//);
  assert.match(manifest.bugs?.url ?? "", /^https:\/\/github\.com\/.*\/issues$/);
  // The docs' repository links agree with package.json's (which comes from Cargo.toml).
  const repository = manifest.repository.url.replace(/^git\+/, "").replace(/\.git$/, "");
  for (const doc of ["README.md", "CHANGELOG.md"]) {
    const text = readFileSync(join(app, "node_modules/arps", doc), "utf8");
    for (const [link] of text.matchAll(/https:\/\/github\.com\/[\w.-]+\/[\w.-]+/g)) {
      assert.equal(link, repository, `${doc} links to ${link}, package.json's repository is ${repository}`);
    }
  }
  console.log(`${packed.filename}: ${files.length} files, ${packed.size} bytes packed, ${packed.unpackedSize} unpacked`);
});

test("npm publish --dry-run prints no warning", async () => {
  const { stdout, stderr } = await run("npm", ["publish", "--dry-run", "--offline"], { cwd: PKG, env });
  // Only the missing login is expected here (this machine publishes nothing).
  const warnings = `${stdout}\n${stderr}`
    .split("\n")
    .filter((l) => /npm warn/i.test(l) && !/requires you to be logged in/.test(l));
  assert.deepEqual(warnings, [], "npm publish --dry-run warned");
  assert.match(stdout + stderr, new RegExp(`arps@${manifest.version.replace(/\./g, "\\.")}`));
});

/**
 * Type-checks and emits a template project with the TypeScript API; returns, per module
 * specifier imported by its files, the names of the value exports the declarations give, and
 * the module format (CommonJS or ESM) of the declaration file it resolved to.
 */
function typescript(config) {
  const host = {
    ...ts.sys,
    onUnRecoverableConfigFileDiagnostic: (d) => assert.fail(ts.flattenDiagnosticMessageText(d.messageText, "\n")),
  };
  const parsed = ts.getParsedCommandLineOfConfigFile(join(app, config), {}, host);
  const program = ts.createProgram({ rootNames: parsed.fileNames, options: parsed.options });
  const emitted = program.emit();
  const diagnostics = [...ts.getPreEmitDiagnostics(program), ...emitted.diagnostics];
  const text = ts.formatDiagnostics(diagnostics, { getCanonicalFileName: (f) => f, getCurrentDirectory: () => app, getNewLine: () => "\n" });
  assert.equal(diagnostics.length, 0, `tsc -p ${config}:\n${text}`);
  const checker = program.getTypeChecker();
  const modules = {};
  for (const file of parsed.fileNames) {
    for (const st of program.getSourceFile(file).statements) {
      if (!ts.isImportDeclaration(st) || !st.moduleSpecifier.text.startsWith("arps")) continue;
      const symbol = checker.getSymbolAtLocation(st.moduleSpecifier);
      assert.ok(symbol, `${config}: "${st.moduleSpecifier.text}" does not resolve`);
      const values = checker
        .getExportsOfModule(symbol)
        .filter((s) => ((s.flags & ts.SymbolFlags.Alias ? checker.getAliasedSymbol(s) : s).flags & ts.SymbolFlags.Value) !== 0)
        .map((s) => s.name);
      const declaration = symbol.declarations[0].getSourceFile();
      modules[st.moduleSpecifier.text] = {
        values: values.sort(),
        file: declaration.fileName.slice(app.length + 1),
        format: declaration.impliedNodeFormat === ts.ModuleKind.CommonJS ? "commonjs" : "esm",
      };
    }
  }
  return modules;
}

/** Runs a node program in the app; returns its stdout parsed as JSON. */
async function nodeJson(args) {
  const { stdout } = await run(process.execPath, args, { cwd: app, env, timeout: 120_000 });
  return JSON.parse(stdout);
}

/** Rotation (degrees) and translation errors of a column-major 4x4 against the pair's truth. */
function errors(m) {
  let trace = 0;
  for (let i = 0; i < 3; i++) for (let k = 0; k < 3; k++) trace += m[k * 4 + i] * TRUTH[i][k];
  const rotationDeg = (Math.acos(Math.min(1, Math.max(-1, (trace - 1) / 2))) * 180) / Math.PI;
  const translation = Math.hypot(m[12] - TRUTH[0][3], m[13] - TRUTH[1][3], m[14] - TRUTH[2][3]);
  return { rotationDeg, translation };
}

function assertRecovered(m, what) {
  assert.equal(m.length, 16, `${what}: not a 4x4`);
  const e = errors(m);
  assert.ok(e.rotationDeg < MAX_ROTATION_DEG && e.translation < MAX_TRANSLATION, `${what}: the pair's transform is not recovered (${JSON.stringify(e)})`);
  return e;
}

const sorted = (a) => [...a].sort();

test("TypeScript and Node, ESM: bundler and NodeNext resolution type-check; the app aligns the pair on the main thread and in a worker", async () => {
  const bundler = typescript("tsconfig.bundler.json");
  const nodenext = typescript("tsconfig.nodenext.json");
  assert.equal(nodenext.arps.format, "esm");
  const out = await nodeJson(["out-esm/node-esm.js", SOURCE, TARGET]);
  assert.equal(out.version, manifest.version);
  console.log("ESM main thread:", JSON.stringify(assertRecovered(out.matrix, "ESM main thread")));
  console.log("ESM worker client:", JSON.stringify(assertRecovered(out.worker.matrix, "ESM worker client")));
  assert.ok(Array.isArray(out.alternatives), "result.alternatives is an array");
  for (const a of out.alternatives) assert.ok(a.matrix.length === 16 && a.fitness >= 0 && a.inlierRmse >= 0, JSON.stringify(a));
  assert.deepEqual(out.worker.stages.at(-1), "done");
  assert.ok(out.worker.stages.every((s) => out.worker.knownStages.includes(s)), `unknown stages ${out.worker.stages}`);
  // Clear errors for misuse.
  assert.match(out.errors.arrayOfArrays ?? "", /source: element 0 is an Array, expected a number/);
  assert.match(out.errors.noFileName ?? "", /no file name was given/);
  assert.match(out.errors.afterFree ?? "", /freed/);
  // The declarations' value exports are the runtime's, entry by entry.
  assert.deepEqual(nodenext.arps.values, sorted(out.keys.arps), "Node ESM: typed vs runtime exports of arps");
  assert.deepEqual(nodenext["arps/worker-client"].values, sorted(out.keys["arps/worker-client"]), "typed vs runtime exports of arps/worker-client");
  const web = await nodeJson(["--input-type=module", "-e", 'import * as m from "arps/web"; console.log(JSON.stringify(Object.keys(m)))']);
  assert.deepEqual(bundler.arps.values, sorted(web), "web build: typed vs runtime exports");
  assert.deepEqual(bundler["arps/worker-client"].values, sorted(out.keys["arps/worker-client"]));
  for (const name of [...web, ...out.keys.arps, ...out.keys.init]) assert.doesNotMatch(name, /^__|wbg|wbindgen|^makeApi$|^glue$/, `internal export ${name}`);
});

test("TypeScript and Node, CommonJS with esModuleInterop: `import init from \"arps\"` type-checks and runs (node10 and Node16)", async () => {
  for (const config of ["cjs/tsconfig.node10.json", "cjs/tsconfig.node16.json"]) {
    const typed = typescript(config);
    if (config.includes("node16")) assert.equal(typed.arps.format, "commonjs", `${config}: the require condition's declarations (${typed.arps.file}) are not CommonJS`);
    const outDir = JSON.parse(readFileSync(join(app, config), "utf8")).compilerOptions.outDir;
    const out = await nodeJson([join("cjs", outDir, "main.js"), SOURCE, TARGET]);
    assert.equal(out.initType, "function", `${config}: the default import is not init()`);
    assert.match(out.errors.afterFree ?? "", /freed/);
    assert.deepEqual(typed.arps.values, sorted(out.keys.arps), `${config}: typed vs runtime exports`);
    for (const name of out.keys.init) assert.doesNotMatch(name, /^__|wbg|wbindgen/, `${config}: init() resolves to internals (${name})`);
    console.log(`${config}:`, JSON.stringify(assertRecovered(out.matrix, config)));
  }
});

test("only the exported entry points can be imported", async () => {
  const exported = pointedAt({ exports: manifest.exports });
  const others = packed.files.map((f) => f.path).filter((f) => /\.[cm]?js$/.test(f) && !exported.has(f));
  const script = `
    const results = {};
    for (const f of ${JSON.stringify(others)}) {
      try { await import("arps/" + f); results[f] = "imported"; } catch (e) { results[f] = e.code ?? e.message; }
    }
    console.log(JSON.stringify(results));`;
  const results = await nodeJson(["--input-type=module", "-e", script]);
  for (const [f, r] of Object.entries(results)) assert.equal(r, "ERR_PACKAGE_PATH_NOT_EXPORTED", `arps/${f}: ${r}`);
});

test("the package's examples/node-register.mjs aligns the pair and writes the aligned source", async () => {
  const moved = join(dir, "source-aligned.ply");
  const out = await nodeJson(["node_modules/arps/examples/node-register.mjs", SOURCE, TARGET, "--json", "--aligned", moved]);
  console.log("examples/node-register.mjs:", JSON.stringify(assertRecovered(out.T_target_source, "examples/node-register.mjs")));
  // the source (an ASCII PLY) written as itself, moved: its header and comment kept
  const head = readFileSync(moved, "latin1").slice(0, 60);
  assert.ok(head.startsWith("ply\nformat ascii 1.0\ncomment arps wasm test fixture"), head);
});

/**
 * Opens `url` (the browser example), uploads the pair, aligns, checks the aligned source's
 * download; returns the parsed #result.
 */
async function alignInBrowser(browser, url) {
  const page = await browser.newPage();
  const problems = [];
  page.on("pageerror", (e) => problems.push(`pageerror: ${e.message}`));
  page.on("console", (m) => m.type() === "error" && problems.push(`console.error: ${m.text()}`));
  page.on("response", (r) => r.status() >= 400 && problems.push(`HTTP ${r.status()}: ${r.url()}`));
  try {
    await page.goto(url);
    await page.setInputFiles("#source-file", SOURCE);
    await page.setInputFiles("#target-file", TARGET);
    await page.click("#align");
    await page.waitForFunction(
      () => document.getElementById("result").textContent || document.getElementById("error").textContent,
      null,
      { timeout: 120_000 },
    );
    assert.equal(await page.textContent("#error"), "", `the page shows an error (${problems.join("; ")})`);
    assert.ok(page.workers().length >= 1, "no worker ran: the example must align through arps/worker-client");
    // the aligned source offered as a download (made in the worker): the PLY file itself, moved
    await page.waitForSelector("#download:not([hidden])", { timeout: 120_000 });
    const saved = await page.evaluate(async () => {
      const a = document.getElementById("download");
      const bytes = new Uint8Array(await (await fetch(a.href)).arrayBuffer());
      return { name: a.download, head: new TextDecoder().decode(bytes.subarray(0, 40)), size: bytes.length };
    });
    assert.equal(saved.name, "source-aligned.ply");
    assert.ok(saved.head.startsWith("ply\nformat ascii 1.0\ncomment arps wasm") && saved.size > 1000, JSON.stringify(saved));
    assert.deepEqual(problems, []);
    return JSON.parse(await page.textContent("#result"));
  } finally {
    await page.close();
  }
}

test("browser: examples/browser built with Vite, and served as plain files, align the pair in Chromium through the worker", async () => {
  const web = join(app, "web");
  cpSync(join(app, "node_modules/arps/examples/browser"), web, { recursive: true });
  await build({ root: web, configFile: false, logLevel: "warn", build: { outDir: "dist", emptyOutDir: true } });
  assert.ok(readdirSync(join(web, "dist")).includes("index.html"));
  const servers = [
    // the Vite build's dist/
    await preview({ root: web, configFile: false, logLevel: "warn", preview: { host: "127.0.0.1", port: 0 } }),
    // the installed package as static files: the example's import map finds worker-client.js
    await preview({
      root: app,
      configFile: false,
      logLevel: "warn",
      build: { outDir: "node_modules/arps" },
      preview: { host: "127.0.0.1", port: 0 },
    }),
  ];
  const browser = await chromium.launch({
    executablePath: CHROMIUM,
    headless: true,
    args: ["--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-background-networking", "--disable-component-update", "--disable-sync"],
  });
  try {
    const [vite, plain] = servers.map((s) => s.resolvedUrls.local[0]);
    const built = await alignInBrowser(browser, vite);
    console.log("Vite build, Chromium, worker:", JSON.stringify(assertRecovered(flatten(built.T_target_source), "Vite build")));
    const statik = await alignInBrowser(browser, new URL("examples/browser/", plain).href);
    console.log("static files, Chromium, worker:", JSON.stringify(assertRecovered(flatten(statik.T_target_source), "static example")));
  } finally {
    await browser.close();
    for (const s of servers) await s.close();
  }
});

/** Row-major rows -> column-major 16. */
function flatten(rows) {
  const m = new Array(16);
  rows.forEach((row, i) => row.forEach((v, k) => (m[k * 4 + i] = v)));
  return m;
}
