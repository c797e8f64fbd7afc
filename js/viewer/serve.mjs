/**
 * A minimal static file server (node:http only) for the viewer, its test and its screenshot.
 *
 *   node js/viewer/serve.mjs [PORT]    # serves js/ on localhost; open /viewer/ there
 *
 * Any static server of js/ (or of the repository root, then open /js/viewer/) does as well,
 * provided it serves .mjs and .js as JavaScript, e.g. `python3 -m http.server -d js`.
 */
import http from 'node:http';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

export const JS_ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');

/** @type {Record<string, string>} */
const TYPES = {
  '.html': 'text/html; charset=utf-8', '.mjs': 'text/javascript', '.js': 'text/javascript',
  '.json': 'application/json', '.css': 'text/css', '.png': 'image/png', '.wasm': 'application/wasm',
};

/**
 * Serves `root` and, under /extra/NAME, the files of `extra` (for a .pln made elsewhere).
 * @param {{root?: string, port?: number, extra?: Record<string, string>}} [options]
 * @returns {Promise<{url: string, close: () => Promise<void>}>} url ends with '/'
 */
export function serve({ root = JS_ROOT, port = 0, extra = {} } = {}) {
  const server = http.createServer((req, res) => {
    const pathname = decodeURIComponent(new URL(req.url ?? '/', 'http://localhost').pathname);
    let file;
    if (pathname.startsWith('/extra/') && Object.hasOwn(extra, pathname.slice(7))) file = extra[pathname.slice(7)];
    else {
      file = path.join(root, path.normalize(pathname));
      if (!file.startsWith(root)) { res.writeHead(403).end(); return; }
      if (fs.existsSync(file) && fs.statSync(file).isDirectory()) {
        if (!pathname.endsWith('/')) { res.writeHead(301, { location: `${pathname}/` }).end(); return; }
        file = path.join(file, 'index.html');
      }
    }
    fs.readFile(file, (err, data) => {
      if (err) { res.writeHead(404, { 'content-type': 'text/plain' }).end('not found'); return; }
      res.writeHead(200, {
        'content-type': TYPES[path.extname(file).toLowerCase()] ?? 'application/octet-stream',
        'cache-control': 'no-store',
      }).end(data);
    });
  });
  return new Promise((resolve, reject) => {
    server.on('error', reject);
    server.listen(port, '127.0.0.1', () => {
      const addr = /** @type {import('node:net').AddressInfo} */ (server.address());
      resolve({
        url: `http://127.0.0.1:${addr.port}/`,
        close: () => new Promise((done) => { server.closeAllConnections(); server.close(() => done()); }),
      });
    });
  });
}

if (process.argv[1] && path.resolve(process.argv[1]) === fileURLToPath(import.meta.url)) {
  const { url } = await serve({ port: Number(process.argv[2] ?? 8080) });
  console.log(`serving ${JS_ROOT} at ${url}: open ${url}viewer/ (Ctrl-C stops)`);
}
