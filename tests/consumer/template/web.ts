// Browser code as a bundler app writes it (type-checked with moduleResolution "bundler"; the
// browser run itself is the package's examples/browser, built with Vite).
import init, { Registrar, parsePointCloud, readPointCloud, version, type RegisterOptions, type RegistrationResult } from "arps";
import { createWorkerRegistrar, STAGES, type Stage, type WorkerRegistrar } from "arps/worker-client";

export async function onMainThread(sourceFile: File, targetFile: File): Promise<number[]> {
  await init();
  const registrar = Registrar.withDefaultModel();
  const source = parsePointCloud(new Uint8Array(await sourceFile.arrayBuffer()), sourceFile.name);
  const target = readPointCloud(new Uint8Array(await targetFile.arrayBuffer()), targetFile.name);
  const options: RegisterOptions = { icp: "plane", seed: 7 };
  const result: RegistrationResult = registrar.register(source, target, options);
  if (result.confidence < 0.5) console.warn(version(), result.warnings);
  registrar.free();
  return result.T_target_source;
}

export async function inAWorker(source: Float32Array, target: Float32Array, signal: AbortSignal): Promise<number[]> {
  const stages: readonly Stage[] = STAGES;
  const arps: WorkerRegistrar = await createWorkerRegistrar({ onProgress: (stage: Stage) => console.log(stage, stages.length) });
  try {
    const r = await arps.register(source, target, { starts: ["network", "global"] }, { signal, onProgress: (s) => void s });
    return r.T_target_source;
  } finally {
    arps.terminate();
  }
}

// @ts-expect-error options are checked: a misspelled option does not type-check
export const misspelled: RegisterOptions = { icpMaxIteration: 3 };
