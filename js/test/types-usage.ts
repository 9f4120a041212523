// Compile-only check of the package's TypeScript declarations (tsc --noEmit -p js/test): typical
// use must type-check, options are typed (not `any`), and misspelled options are rejected.
import init, { canTransform, initSync, listScans, Registrar, parsePointCloud, readPointCloud, rigidFromPairs, transformFile, transformPointCloud, version, writePly } from "../../pkg/arps.js";
import type { InitOptions, PairsFit, RegisterOptions, RegistrationEvidence, RegistrationResult, RegistrationSearch, ScanInfo, WarningCode } from "../../pkg/arps.js";
import { createWorkerRegistrar, type Stage, type WorkerRegistrar } from "../../pkg/worker-client.js";

export async function modelFiles(wasm: Uint8Array, model: Uint8Array, signal: AbortSignal): Promise<Registrar> {
  // The default model: fetched by init() (or not, or from elsewhere), or given to initSync.
  await init({ model: false });
  await init({ module_or_path: wasm, model: "https://cdn.example/arps-web.safetensors" });
  await init({ model: new URL("https://cdn.example/m.safetensors") });
  initSync({ module: wasm, model });
  initSync({ module: wasm });
  // @ts-expect-error model is a URL, bytes, a Response or a boolean
  const bad: InitOptions = { model: 3 };
  void bad;
  const fromUrl: Registrar = await Registrar.fromUrl("/models/custom.safetensors", { signal });
  fromUrl.free();
  // @ts-expect-error fromUrl is async
  Registrar.fromUrl("/m.safetensors").register(new Float32Array(), new Float32Array());
  const w = await createWorkerRegistrar({ model: "/m.safetensors", weights: new URL("https://cdn.example/w.safetensors") });
  w.terminate();
  return Registrar.withDefaultModel();
}

export async function onMainThread(source: Float32Array, target: Float32Array): Promise<number> {
  await init();
  const r = Registrar.withDefaultModel();
  const options: RegisterOptions = { icp: "plane", seed: 3, maxCorrespondenceDistance: 0.05, nonFinite: "drop", outliers: "keep", supportPlane: "keep" };
  const result: RegistrationResult = r.register(source, target, options);
  const m: number[] = result.T_target_source;
  const again = r.register(source, target, { initialTransform: m, network: false });
  r.register(source, target);
  r.register(source, target, null);
  const ms: number = again.timings.totalMs + result.fitness + result.inlierRmse + result.icpIterations;
  const w: string[] = result.warnings;
  const codes: WarningCode[] = result.warningCodes;
  const unitsDiffer: boolean = result.warningCodes.includes("sizeMismatch");
  // @ts-expect-error a code that does not exist
  const misspelt: WarningCode = "sizeMissmatch";
  void codes, unitsDiffer, misspelt;
  const start: "network" | "centroids" | "initial" | "turned" | "turnedInitial" | "global" | "globalNetwork" | "rotations" | "rotationsNetwork" = result.start;
  r.register(source, target, { starts: ["network", "initial"] });
  r.register(source, target, { starts: ["turned", "turnedInitial", "rotations", "rotationsNetwork"] });
  r.register(source, target, { starts: ["network", "global", "globalNetwork"], search: "exhaustive" });
  const search: RegistrationSearch = "adaptive";
  r.register(source, target, { search });
  // How sure the engine is, and why.
  const confidence: number = result.confidence;
  const evidence: RegistrationEvidence = result.evidence;
  const figures: number =
    evidence.fitness + evidence.fitnessTight + evidence.fitnessLoose + evidence.fitnessCoarse +
    evidence.overlapReverse + evidence.rmseRatio + evidence.ambiguity + evidence.alternatives + evidence.slide + result.startsRefined + result.timings.globalMs;
  // @ts-expect-error the evidence is camelCase
  const snakeEvidence = result.evidence.overlap_reverse;
  // @ts-expect-error misspelled search value
  r.register(source, target, { search: "exhaustve" });
  // @ts-expect-error search is a name, not a flag
  r.register(source, target, { search: true });
  // @ts-expect-error unknown start
  r.register(source, target, { starts: ["identity"] });
  const kind: string | undefined = r.provenance.kind;
  const networkPoints: number = r.modelConfig.nPoints;
  const reference: "top_h" | "soft" = r.modelConfig.reference;
  // @ts-expect-error the config is camelCase
  const snake = r.modelConfig.n_points;
  // @ts-expect-error misspelled option
  r.register(source, target, { icpMaxIteration: 3 });
  // @ts-expect-error wrong enum value
  r.register(source, target, { icp: "planar" });
  // Large coordinates: Float64Array or { points, origin } in, T_target_source in the caller's frame out.
  const far: number[] = result.T_target_source;
  r.register(new Float64Array(source), { points: target, origin: [5e5, 4e6, 0] }).T_target_source.length;
  const read = readPointCloud(new Uint8Array(), "far.ply");
  r.register(read, read.points);
  // A mesh read as its sampled surface; the read options are checked like the register options.
  r.register(parsePointCloud(new Uint8Array(), "model.stl", { surfacePoints: 100_000, seed: 2 }), readPointCloud(new Uint8Array(), "m.obj", {}));
  // @ts-expect-error misspelled read option
  parsePointCloud(new Uint8Array(), "model.stl", { surfacePoint: 100_000 });
  // @ts-expect-error a cloud is not a string
  r.register("1 2 3", target);
  // The registered source saved in the target's frame: moved (origin kept), then PLY bytes.
  const aligned: Float32Array = transformPointCloud(read, result.T_target_source).points;
  const bytes: Uint8Array = writePly(transformPointCloud(new Float64Array(source), [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]));
  // @ts-expect-error the matrix comes second
  transformPointCloud(result.T_target_source);
  // A guess from paired landmarks: packed numbers or rows of [x, y, z].
  const pairs: PairsFit = rigidFromPairs([[0, 0, 0], [1, 0, 0], [0, 1, 0]], new Float64Array([1, 0, 0, 2, 0, 0, 1, 1, 0]));
  const pairsRmse: number = pairs.rmse;
  // A file moved as it is, in its own format (colours, normals and faces kept).
  const movedFile: Uint8Array = transformFile(new Uint8Array(), "scan.pcd", result.T_target_source);
  const movedSurvey: Uint8Array = canTransform("survey.las") ? transformFile(new Uint8Array(), "survey.las", result.T_target_source) : new Uint8Array();
  // the package's own bytes read back (TypeScript 5.7+ types them Uint8Array<ArrayBufferLike>), and a DataView
  parsePointCloud(bytes, "aligned.ply");
  readPointCloud(transformFile(movedFile, "scan.pcd", result.T_target_source), "scan.pcd");
  parsePointCloud(new DataView(bytes.buffer), "aligned.ply");
  const scans: ScanInfo[] = listScans(new Uint8Array(), "scan.e57");
  const firstName: string | null = scans[0]?.name ?? null;
  // @ts-expect-error the file's name comes second
  transformFile(new Uint8Array(), result.T_target_source);
  r.free();
  return far.length + ms + confidence + figures + String(snakeEvidence).length + networkPoints + reference.length + String(snake).length + w.length + start.length + version().length + (kind?.length ?? 0) + parsePointCloud(new Uint8Array(), "a.ply").length + aligned.length + bytes.length + movedFile.length + movedSurvey.length + (firstName?.length ?? 0);
}

export async function inAWorker(source: Float32Array, target: Float32Array): Promise<number[]> {
  const arps: WorkerRegistrar = await createWorkerRegistrar({ onProgress: (s: Stage) => void s });
  const controller = new AbortController();
  const result = await arps.register(source, target, { icp: "point" }, { onProgress: (s) => void s, transfer: true, signal: controller.signal });
  await createWorkerRegistrar({ createWorker: () => new Worker(new URL("./worker.js", import.meta.url), { type: "module" }) });
  const points: Float32Array = await arps.parsePointCloud(new Uint8Array(), "cloud.pcd");
  await arps.parsePointCloud(new DataView(new ArrayBuffer(8)), "cloud.pcd");
  const surface: Float32Array = await arps.parsePointCloud(new Uint8Array(), "model.stl", { surfacePoints: 50_000 }, { transfer: true });
  // @ts-expect-error the request comes after the read options
  await arps.parsePointCloud(new Uint8Array(), "model.stl", { surfacePoints: 50_000, transfer: true });
  const cloud = await arps.readPointCloud(new Uint8Array(), "cloud.pcd");
  const fromWorker = await arps.register(cloud, points, { search: "exhaustive" });
  if (fromWorker.confidence < 0.5) console.warn(fromWorker.warnings, fromWorker.evidence.ambiguity);
  const ply: Uint8Array = await arps.writePly(await arps.transformPointCloud(cloud, fromWorker.T_target_source), { transfer: true });
  const forgotten: void = await arps.forgetTarget({ signal: controller.signal });
  void forgotten;
  arps.terminate();
  return points.length + surface.length + ply.length ? result.T_target_source : result.T_target_source_network;
}
