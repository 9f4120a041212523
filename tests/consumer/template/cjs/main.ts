// A CommonJS app (package "type": "commonjs") with esModuleInterop: the default import is
// init(). Type-checked and compiled twice (module "CommonJS" with node10 resolution, and
// "Node16"), then run: registers the two files given on the command line and prints one JSON object.
import { readFileSync } from "fs";
import { basename } from "path";
import init, { Registrar, parsePointCloud, version } from "arps";
import * as arps from "arps";

async function main(): Promise<void> {
  const [sourcePath, targetPath] = process.argv.slice(2);
  const initKeys = Object.keys((await init()) as object); // (not part of the API: checked not to be the raw glue)
  const source = parsePointCloud(readFileSync(sourcePath), basename(sourcePath));
  const target = parsePointCloud(readFileSync(targetPath), basename(targetPath));
  const registrar = Registrar.withDefaultModel();
  const result = registrar.register(source, target, { seed: 1 });
  registrar.free();
  let afterFree: string | null = null;
  try {
    registrar.register(source, target);
  } catch (e) {
    afterFree = e instanceof Error ? e.message : String(e);
  }
  console.log(
    JSON.stringify({
      version: version(),
      initType: typeof init,
      matrix: Array.from(result.T_target_source),
      confidence: result.confidence,
      errors: { afterFree },
      keys: { init: initKeys, arps: Object.keys(arps) },
    }),
  );
}

main().catch((e) => {
  console.error(e);
  process.exit(1);
});
