#!/usr/bin/env node
// Saving a registered source, in Node (after scripts/build-pkg.sh): transformPly on a made
// 1M-point binary PLY (x y z nx ny nz float, red green blue uchar), against reading it and writing
// its points (readPointCloud, transformPointCloud, writePly). Prints the medians of 5.
import { readPointCloud, transformPly, transformPointCloud, writePly } from "../pkg/node/index.mjs";
const n = 1_000_000;
const head = `ply\nformat binary_little_endian 1.0\nelement vertex ${n}\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n`;
const bytes = new Uint8Array(head.length + n * 27);
bytes.set(new TextEncoder().encode(head));
const view = new DataView(bytes.buffer, head.length);
for (let i = 0; i < n; i++) {
  const o = i * 27;
  view.setFloat32(o, Math.sin(i) * 10, true); view.setFloat32(o + 4, Math.cos(i * 0.7) * 10, true); view.setFloat32(o + 8, (i % 1000) * 0.01, true);
  view.setFloat32(o + 12, 0, true); view.setFloat32(o + 16, 0, true); view.setFloat32(o + 20, 1, true);
  view.setUint8(o + 24, i & 255); view.setUint8(o + 25, 7); view.setUint8(o + 26, 9);
}
const a = 0.3;
const T = [Math.cos(a), Math.sin(a), 0, 0, -Math.sin(a), Math.cos(a), 0, 0, 0, 0, 1, 0, 1, 2, 3, 1];
const median = (f) => { const t = []; for (let k = 0; k < 5; k++) { const t0 = performance.now(); f(); t.push(performance.now() - t0); } t.sort((x, y) => x - y); return t[2]; };
const moved = median(() => transformPly(bytes, T));
const points = median(() => writePly(transformPointCloud(readPointCloud(bytes, "a.ply"), T)));
console.log(`1,000,000 points, ${(bytes.length / 1e6).toFixed(1)} MB: transformPly ${moved.toFixed(0)} ms; readPointCloud + transformPointCloud + writePly ${points.toFixed(0)} ms (median of 5)`);
