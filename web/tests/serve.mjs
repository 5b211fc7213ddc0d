// Serves the explorer's files (web/, not web/tests/) on a free localhost
// port for the browser tests (explorer.test.mjs, realtime.test.mjs); resolves to the listening http.Server.

import { createServer } from 'node:http';
import { readFile } from 'node:fs/promises';
import { extname, resolve } from 'node:path';

const TYPES = { '.html': 'text/html', '.js': 'text/javascript', '.css': 'text/css', '.wasm': 'application/wasm', '.glsl': 'text/plain' };

export function serveWeb(webRoot) {
  const server = createServer(async (request, response) => {
    const path = new URL(request.url, 'http://localhost').pathname;
    const file = resolve(webRoot, `.${path === '/' ? '/index.html' : path}`);
    if (!file.startsWith(webRoot) || file.includes('/tests/')) {
      response.writeHead(404).end();
      return;
    }
    try {
      const body = await readFile(file);
      response.writeHead(200, { 'content-type': TYPES[extname(file)] || 'application/octet-stream' }).end(body);
    } catch {
      response.writeHead(404).end();
    }
  });
  return new Promise((ok) => server.listen(0, '127.0.0.1', () => ok(server)));
}
