// The explorer's engine thread: loads sora_web.wasm (the sora library
// compiled to WebAssembly, crates/sora-web) and answers the page's requests
// one at a time, so that the page never freezes while a sky is computed.
//
// Message in:  {id, request}            (request: see crates/sora-web/src/request.rs)
// Message out: {id, ok, json, bytes, ms} (bytes: an ArrayBuffer, transferred;
//              ms: the engine's wall time for this request)
//              or {id: 0, ready: true} / {id: 0, ok: false, json: {error}} once loaded;
//              during a long request (the engine tables' bake) also
//              {id, progress} (the fraction of its work done, as the engine
//              reports it through its env.sora_progress import).

let engine = null;
let running = 0; // the id of the request being computed

async function load() {
  const response = await fetch(new URL('./sora_web.wasm', import.meta.url));
  if (!response.ok) throw new Error(`sora_web.wasm: HTTP ${response.status} (build it with crates/sora-web/build.sh)`);
  const imports = { env: { sora_progress: (fraction) => self.postMessage({ id: running, progress: fraction }) } };
  const { instance } = await WebAssembly.instantiate(await response.arrayBuffer(), imports);
  engine = instance.exports;
}

function call(request) {
  const text = new TextEncoder().encode(JSON.stringify(request));
  const pointer = engine.sora_alloc(text.length);
  new Uint8Array(engine.memory.buffer, pointer, text.length).set(text);
  const started = performance.now();
  const status = engine.sora_call(pointer, text.length);
  const ms = performance.now() - started;
  engine.sora_free(pointer, text.length);
  // The memory may have grown during the call: views are made after it.
  const memory = engine.memory.buffer;
  const json = JSON.parse(new TextDecoder().decode(
    new Uint8Array(memory, engine.sora_reply_json_ptr(), engine.sora_reply_json_len())));
  const bytes = new Uint8Array(memory, engine.sora_reply_bytes_ptr(), engine.sora_reply_bytes_len()).slice().buffer;
  return { ok: status === 0, json, bytes, ms };
}

const loaded = load().then(
  () => self.postMessage({ id: 0, ready: true }),
  (error) => self.postMessage({ id: 0, ok: false, json: { error: String(error.message || error) } }),
);

self.onmessage = async (event) => {
  await loaded;
  const { id, request } = event.data;
  if (!engine) {
    self.postMessage({ id, ok: false, json: { error: 'the engine did not load' }, bytes: new ArrayBuffer(0), ms: 0 });
    return;
  }
  running = id;
  const reply = call(request);
  self.postMessage({ id, ...reply }, [reply.bytes]);
};
