// A Node ES module app (type-checked with module "NodeNext", compiled, then run): registers the
// two files given on the command line on the main thread and through the worker client, checks
// the clear errors of misuse, and prints what it found as one JSON object.
import { readFileSync } from "node:fs";
import { basename } from "node:path";
import init, { Registrar, parsePointCloud, readPointCloud, version } from "arps";
import * as arps from "arps";
import type { RegistrationAlternative } from "arps";
import { createWorkerRegistrar, STAGES } from "arps/worker-client";
import * as workerClient from "arps/worker-client";

/** The message of what `f` throws (an `Error` is expected), or null when it does not throw. */
function thrown(f: () => unknown): string | null {
  try {
    f();
    return null;
  } catch (e) {
    return e instanceof Error ? e.message : `not an Error: ${String(e)}`;
  }
}

const [sourcePath, targetPath] = process.argv.slice(2);
const sourceBytes = readFileSync(sourcePath);
const targetBytes = readFileSync(targetPath);

// Under Node init() is a no-op; what it resolves to must not be the raw glue.
const initKeys = Object.keys((await init()) as object); // (not part of the API: checked not to be the raw glue)
const registrar = Registrar.withDefaultModel();
const source: Float32Array = parsePointCloud(sourceBytes, basename(sourcePath));
const target = readPointCloud(targetBytes, basename(targetPath));
const result = registrar.register(source, target, { seed: 1 });
// the other poses that fit about as well (none expected on this distinct pair), typed
const lookAlikes: RegistrationAlternative[] = result.alternatives;

const errors = {
  // @ts-expect-error a cloud is packed xyz, not an array of [x, y, z] arrays
  arrayOfArrays: thrown(() => registrar.register([[0, 0, 0], [1, 0, 0]], target)),
  // @ts-expect-error the file name is required
  noFileName: thrown(() => parsePointCloud(new TextEncoder().encode("not a point cloud\n"))),
  afterFree: thrown(() => {
    registrar.free();
    registrar.register(source, target);
  }),
};

const worker = await createWorkerRegistrar();
const workerSource = await worker.parsePointCloud(sourceBytes, basename(sourcePath));
const workerTarget = await worker.readPointCloud(targetBytes, basename(targetPath));
const stages: string[] = [];
const fromWorker = await worker.register(workerSource, workerTarget, { seed: 1 }, { onProgress: (s) => stages.push(s) });
worker.terminate();

console.log(
  JSON.stringify({
    version: version(),
    matrix: Array.from(result.T_target_source),
    confidence: result.confidence,
    alternatives: lookAlikes.map((a) => ({ matrix: Array.from(a.T_target_source), fitness: a.fitness, inlierRmse: a.inlierRmse })),
    worker: { matrix: Array.from(fromWorker.T_target_source), stages, knownStages: STAGES },
    errors,
    keys: { init: initKeys, arps: Object.keys(arps), "arps/worker-client": Object.keys(workerClient) },
  }),
);
