// A tiny static file server for the demo page (scripts/demo.sh, tests/e2e/): serves the repo root
// on 127.0.0.1 so the page at /www/ reaches /pkg/ (the built package) and /node_modules/three/,
// /node_modules/bunny/ through relative paths, exactly as any static host of the same layout would.
// Only those folders are served; no COOP/COEP headers (the page does not need them).
//   node scripts/serve.mjs [--port N]      (default 8080; 0 picks a free port)
import { createServer } from "node:http";
import { createReadStream, statSync } from "node:fs";
import { extname, join, normalize, resolve, sep } from "node:path";
import { fileURLToPath } from "node:url";

const ROOT = resolve(fileURLToPath(new URL("..", import.meta.url)));
const SERVED = ["/www/", "/pkg/", "/node_modules/three/", "/node_modules/bunny/"];
const TYPES = {
  ".html": "text/html; charset=utf-8",
  ".js": "text/javascript; charset=utf-8",
  ".mjs": "text/javascript; charset=utf-8",
  ".css": "text/css; charset=utf-8",
  ".json": "application/json; charset=utf-8",
  ".wasm": "application/wasm",
  ".png": "image/png",
  ".svg": "image/svg+xml",
  ".ico": "image/x-icon",
  ".ply": "application/octet-stream",
  ".txt": "text/plain; charset=utf-8",
  ".md": "text/plain; charset=utf-8",
  ".ts": "text/plain; charset=utf-8",
};

function handler(req, res) {
  const send = (status, text, headers = {}) => {
    res.writeHead(status, { "content-type": "text/plain; charset=utf-8", ...headers });
    res.end(text);
  };
  if (req.method !== "GET" && req.method !== "HEAD") return send(405, "method not allowed\n");
  let path;
  try {
    path = decodeURIComponent(new URL(req.url, "http://localhost").pathname);
  } catch {
    return send(400, "bad request\n");
  }
  if (path === "/" || path === "/www") return send(302, "", { location: "/www/" });
  if (path.endsWith("/")) path += "index.html";
  const clean = normalize(path).split(sep).join("/");
  if (!SERVED.some((p) => clean.startsWith(p))) return send(404, "not found\n");
  const file = join(ROOT, clean);
  if (!file.startsWith(ROOT + sep)) return send(404, "not found\n");
  let st;
  try {
    st = statSync(file);
  } catch {
    return send(404, "not found\n");
  }
  if (st.isDirectory()) return send(302, "", { location: `${path}/` });
  res.writeHead(200, {
    "content-type": TYPES[extname(file).toLowerCase()] ?? "application/octet-stream",
    "content-length": st.size,
    "cache-control": "no-cache",
  });
  if (req.method === "HEAD") return res.end();
  createReadStream(file).pipe(res);
}

/** Starts the server; resolves to `{ server, url }` (the page's URL). */
export function serve({ port = 8080, host = "127.0.0.1" } = {}) {
  const server = createServer(handler);
  return new Promise((resolvePromise, reject) => {
    server.once("error", reject);
    server.listen(port, host, () => {
      const { port: actual } = server.address();
      resolvePromise({ server, url: `http://${host}:${actual}/www/` });
    });
  });
}

if (process.argv[1] && resolve(process.argv[1]) === fileURLToPath(import.meta.url)) {
  const i = process.argv.indexOf("--port");
  const port = i > 0 ? Number(process.argv[i + 1]) : Number(process.env.PORT ?? 8080);
  serve({ port })
    .then(({ url }) => console.log(`arps demo: ${url}   (Ctrl-C stops)`))
    .catch((e) => {
      console.error(`serve: ${e.message}`);
      process.exit(1);
    });
}
