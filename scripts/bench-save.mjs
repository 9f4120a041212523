#!/usr/bin/env node
// Saving a registered source, in Node (after scripts/build-pkg.sh): transformFile on the same made
// 1M-point cloud (x y z, normals, an 8-bit colour) as binary PLY, binary PCD and an XYZ text list
// (millimetre decimals), against reading it and writing its points as PLY (readPointCloud,
// transformPointCloud, writePly). Prints the medians of 5 per format. Files named on the command
// line (a LAZ survey, say) are timed the same way: node scripts/bench-save.mjs [FILE ...]
import { readFileSync } from "node:fs";
import { basename } from "node:path";
import { readPointCloud, transformFile, transformPointCloud, writePly } from "../pkg/node/index.mjs";
const n = 1_000_000;
const point = (i) => [Math.sin(i) * 10, Math.cos(i * 0.7) * 10, (i % 1000) * 0.01];
const a = 0.3;
const c = Math.cos(a);
const s = Math.sin(a);
const files = {};
{
  // binary PLY and PCD: x y z nx ny nz float, then the colour (PLY: 3 uchar; PCD: one packed float)
  const ply = `ply\nformat binary_little_endian 1.0\nelement vertex ${n}\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n`;
  const pcd = `VERSION 0.7\nFIELDS x y z normal_x normal_y normal_z rgb\nSIZE 4 4 4 4 4 4 4\nTYPE F F F F F F F\nCOUNT 1 1 1 1 1 1 1\nWIDTH ${n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS ${n}\nDATA binary\n`;
  for (const [name, head, stride] of [["cloud.ply", ply, 27], ["cloud.pcd", pcd, 28]]) {
    const bytes = new Uint8Array(head.length + n * stride);
    bytes.set(new TextEncoder().encode(head));
    const view = new DataView(bytes.buffer, head.length);
    for (let i = 0; i < n; i++) {
      const o = i * stride;
      point(i).forEach((v, k) => view.setFloat32(o + 4 * k, v, true));
      view.setFloat32(o + 20, 1, true);
      view.setUint8(o + 24, i & 255); view.setUint8(o + 25, 7); view.setUint8(o + 26, 9);
    }
    files[name] = bytes;
  }
  // an XYZ list: x y z with millimetre decimals, then r g b
  const lines = [];
  for (let i = 0; i < n; i++) lines.push(`${point(i).map((v) => v.toFixed(3)).join(" ")} ${i & 255} 7 9\n`);
  files["cloud.xyz"] = new TextEncoder().encode(lines.join(""));
}
for (const f of process.argv.slice(2)) files[basename(f)] = new Uint8Array(readFileSync(f));
const T = [c, s, 0, 0, -s, c, 0, 0, 0, 0, 1, 0, 1, 2, 3, 1];
const median = (f) => { const t = []; for (let k = 0; k < 5; k++) { const t0 = performance.now(); f(); t.push(performance.now() - t0); } t.sort((x, y) => x - y); return t[2]; };
for (const [name, bytes] of Object.entries(files)) {
  const moved = median(() => transformFile(bytes, name, T));
  const points = median(() => writePly(transformPointCloud(readPointCloud(bytes, name), T)));
  const count = readPointCloud(bytes, name).points.length / 3;
  console.log(`${name}: ${count.toLocaleString("en-US")} points, ${(bytes.length / 1e6).toFixed(1)} MB: transformFile ${moved.toFixed(0)} ms; readPointCloud + transformPointCloud + writePly ${points.toFixed(0)} ms (median of 5)`);
}
