// The browser example's script (index.html): reads the two chosen files, aligns them in a worker
// through arps/worker-client, prints T_target_source (row-major rows, as people read matrices;
// `result.T_target_source` itself is column-major for three.js `Matrix4.fromArray`), and offers
// the source moved into the target's frame as a download (its own format when it can be moved).
import { createWorkerRegistrar } from "arps/worker-client";

const $ = (id) => document.getElementById(id);
const status = (text) => ($("status").textContent = text);

/** One worker for the page, started on the first click (it loads the engine and the model). */
let registrar = null;
async function engine() {
  registrar ??= await createWorkerRegistrar({ onProgress: (stage) => status(`engine: ${stage}`) });
  return registrar;
}

$("align").addEventListener("click", async () => {
  $("error").textContent = "";
  $("result").textContent = "";
  $("download").hidden = true;
  const files = [$("source-file").files[0], $("target-file").files[0]];
  if (!files[0] || !files[1]) {
    $("error").textContent = "choose a source file and a target file";
    return;
  }
  $("align").disabled = true;
  try {
    const arps = await engine();
    // readPointCloud keeps large coordinates exact ({ points, origin }); register takes it as is.
    const [source, target] = await Promise.all(
      files.map(async (f) => arps.readPointCloud(new Uint8Array(await f.arrayBuffer()), f.name)),
    );
    const t0 = performance.now();
    const r = await arps.register(source, target, {}, { onProgress: (stage) => status(`registering: ${stage}`) });
    const m = r.T_target_source; // column-major, f64, exact in the files' frame
    const rows = [0, 1, 2, 3].map((row) => [0, 1, 2, 3].map((col) => m[col * 4 + row]));
    $("result").textContent = JSON.stringify(
      {
        T_target_source: rows,
        confidence: r.confidence,
        fitness: r.fitness,
        inlierRmse: r.inlierRmse,
        start: r.start,
        warnings: r.warnings,
        sourcePoints: source.points.length / 3,
        targetPoints: target.points.length / 3,
      },
      null,
      2,
    );
    status(`done in ${(performance.now() - t0).toFixed(0)} ms (confidence ${r.confidence.toFixed(2)})`);
    // The source saved in the target's frame, in the worker, offered as a download: its own file
    // moved as it is (colours, normals, attributes kept), or, for a file that cannot be (a float
    // STL or PCD moved too far for float32, a name without an extension), its points moved (the
    // origin in f64) and written as PLY.
    let ext = /\.([a-z0-9]+)$/i.exec(files[0].name)?.[1].toLowerCase();
    const own = new Uint8Array(await files[0].arrayBuffer());
    let bytes = ext ? await arps.transformFile(own, files[0].name, m, null, { transfer: true }).catch(() => null) : null;
    if (!bytes) {
      ext = "ply";
      bytes = await arps.writePly(await arps.transformPointCloud(source, m, { transfer: true }), { transfer: true });
    }
    const link = $("download");
    if (link.href) URL.revokeObjectURL(link.href);
    link.href = URL.createObjectURL(new Blob([bytes], { type: "application/octet-stream" }));
    link.download = `${files[0].name.replace(/\.[^.]*$/, "") || "source"}-aligned.${ext}`;
    link.hidden = false;
  } catch (e) {
    $("error").textContent = e.message;
    status("failed");
  } finally {
    $("align").disabled = false;
  }
});
