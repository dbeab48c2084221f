// A static HTTP server on 127.0.0.1 for the Studio host page: /studio/ (this folder's host page), /assets/
// (@foxglove/studio-base's webpack build as installed by `npm ci`), /vendor/ (React 17's UMD builds) and
// /files/NAME (files the caller names: the layout, recordings; byte ranges, as Studio's remote-file source
// reads an MCAP with range requests).
import { createReadStream, statSync } from "node:fs";
import { createServer } from "node:http";
import { dirname, extname, join, normalize, sep } from "node:path";
import { fileURLToPath } from "node:url";

const HERE = dirname(fileURLToPath(import.meta.url));
const MODULES = join(HERE, "node_modules");
const ROOTS = {
  "/studio/": join(HERE, "studio"),
  "/assets/": join(MODULES, "@foxglove", "studio-base", "assets"),
};
const VENDOR = {
  "/vendor/react.production.min.js": join(MODULES, "react", "umd", "react.production.min.js"),
  "/vendor/react-dom.production.min.js": join(MODULES, "react-dom", "umd", "react-dom.production.min.js"),
};
const TYPES = {
  ".html": "text/html; charset=utf-8", ".js": "text/javascript; charset=utf-8", ".json": "application/json",
  ".wasm": "application/wasm", ".css": "text/css", ".png": "image/png", ".svg": "image/svg+xml",
  ".woff2": "font/woff2", ".woff": "font/woff", ".ttf": "font/ttf", ".mcap": "application/octet-stream",
};

function resolve(pathname, files) {
  if (VENDOR[pathname]) return VENDOR[pathname];
  if (pathname.startsWith("/files/")) return files[decodeURIComponent(pathname.slice(7))];
  for (const [prefix, root] of Object.entries(ROOTS)) {
    if (pathname.startsWith(prefix)) {
      const p = normalize(join(root, decodeURIComponent(pathname.slice(prefix.length))));
      return p.startsWith(root + sep) ? p : undefined;
    }
  }
  return undefined;
}

/** Serve on 127.0.0.1 (any free port); `files`: {name: absolute path}. Resolves to {server, origin, log}. */
export function serve(files = {}) {
  const log = [];
  const server = createServer((req, res) => {
    const url = new URL(req.url, "http://127.0.0.1");
    const path = resolve(url.pathname, files);
    let st;
    try {
      st = path && statSync(path);
    } catch {
      st = undefined;
    }
    if (!st || !st.isFile()) {
      log.push(`404 ${url.pathname}`);
      res.writeHead(404, { "content-type": "text/plain" }).end("not found");
      return;
    }
    const headers = {
      "content-type": TYPES[extname(path)] ?? "application/octet-stream", "accept-ranges": "bytes",
      "access-control-allow-origin": "*",
      // Studio's build (56 MB) is parsed once per browser; the named files may change between loads
      "cache-control": url.pathname.startsWith("/files/") ? "no-store" : "max-age=3600",
    };
    const range = /^bytes=(\d*)-(\d*)$/.exec(req.headers.range ?? "");
    let start = 0;
    let end = st.size - 1;
    let status = 200;
    if (range) {
      if (range[1] === "") {
        start = Math.max(0, st.size - Number(range[2]));
      } else {
        start = Number(range[1]);
        if (range[2] !== "") end = Math.min(end, Number(range[2]));
      }
      if (start > end || start >= st.size) {
        res.writeHead(416, { "content-range": `bytes */${st.size}` }).end();
        return;
      }
      status = 206;
      headers["content-range"] = `bytes ${start}-${end}/${st.size}`;
    }
    headers["content-length"] = String(end - start + 1);
    res.writeHead(status, headers);
    if (req.method === "HEAD") {
      res.end();
      return;
    }
    createReadStream(path, { start, end }).pipe(res);
  });
  return new Promise((ok, fail) => {
    server.once("error", fail);
    server.listen(0, "127.0.0.1", () => ok({ server, origin: `http://127.0.0.1:${server.address().port}`, log }));
  });
}
