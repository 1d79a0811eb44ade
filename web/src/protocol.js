// The PVS streaming protocol over a WebSocket (docs/protocol.md, "PVS streaming" and
// "WebSocket"): one binary message per frame, the same 12-byte header and payloads the native
// client sends over TCP. Every parser checks lengths and throws Error on a malformed message.

export const Message = { hello: 1, welcome: 2, fetch: 3, rows: 4, object: 5, done: 6, error: 7, catalogRequest: 8, catalog: 9 };
const kMagic = [0x43, 0x57, 0x4e, 0x50]; // "CWNP"
const kHeaderBytes = 12;
const kProtocolVersion = 1;
const kPvsProtocolVersion = 1;
export const kNoCell = 0xffffffff;

export function frame(type, payload = new Uint8Array(0)) {
  const out = new Uint8Array(kHeaderBytes + payload.byteLength);
  out.set(kMagic, 0);
  out[4] = kProtocolVersion;
  out[5] = type;
  new DataView(out.buffer).setUint32(8, payload.byteLength, true);
  out.set(payload, kHeaderBytes);
  return out;
}

// { type, payload: DataView } of one WebSocket message.
export function parseFrame(buffer) {
  if (buffer.byteLength < kHeaderBytes) throw new Error('a message shorter than a frame header');
  const bytes = new Uint8Array(buffer);
  for (let i = 0; i < 4; ++i) if (bytes[i] !== kMagic[i]) throw new Error('not a cellwalk frame (bad magic)');
  if (bytes[4] !== kProtocolVersion) throw new Error(`protocol version ${bytes[4]}, this page speaks ${kProtocolVersion}`);
  if (bytes[6] !== 0 || bytes[7] !== 0) throw new Error('reserved header bytes are not zero');
  const length = new DataView(buffer).getUint32(8, true);
  if (length !== buffer.byteLength - kHeaderBytes) throw new Error('a frame whose length is not its message\'s');
  return { type: bytes[5], payload: new DataView(buffer, kHeaderBytes, length) };
}

// Reads little-endian fields in order; throws when the message ends too soon.
class Reader {
  constructor(view, what) { this.view = view; this.at = 0; this.what = what; }
  need(n) { if (this.at + n > this.view.byteLength) throw new Error(`a malformed ${this.what} message: it ends too soon`); }
  u32() { this.need(4); const v = this.view.getUint32(this.at, true); this.at += 4; return v; }
  u64() { this.need(8); const v = Number(this.view.getBigUint64(this.at, true)); this.at += 8; return v; }
  f32() { this.need(4); const v = this.view.getFloat32(this.at, true); this.at += 4; return v; }
  f64() { this.need(8); const v = this.view.getFloat64(this.at, true); this.at += 8; return v; }
  u32s(n) {
    this.need(4 * n);
    const out = new Uint32Array(n);
    for (let i = 0; i < n; ++i) out[i] = this.view.getUint32(this.at + 4 * i, true);
    this.at += 4 * n;
    return out;
  }
  bytes(n) {
    this.need(n);
    const out = new Uint8Array(this.view.buffer, this.view.byteOffset + this.at, n);
    this.at += n;
    return out;
  }
  end() { if (this.at !== this.view.byteLength) throw new Error(`a ${this.what} message with ${this.view.byteLength - this.at} bytes too many`); }
}

export function hello() {
  const p = new Uint8Array(4);
  new DataView(p.buffer).setUint32(0, kPvsProtocolVersion, true);
  return frame(Message.hello, p);
}

export function catalogRequest() { return frame(Message.catalogRequest); }

export function fetchRequest(sequence, level, cells, dropped) {
  const p = new DataView(new ArrayBuffer(16 + 4 * (cells.length + dropped.length)));
  let at = 0;
  const put = (v) => { p.setUint32(at, v, true); at += 4; };
  put(sequence); put(level);
  put(cells.length); cells.forEach(put);
  put(dropped.length); dropped.forEach(put);
  return frame(Message.fetch, new Uint8Array(p.buffer));
}

export function parseWelcome(view) {
  const r = new Reader(view, 'welcome');
  const w = { worldBytes: r.u64(), objects: r.u32(), cellCount: r.u32(), originX: r.f64(), originZ: r.f64(), cellSize: r.f64(), rows: r.u32(), cols: r.u32() };
  if (!(w.cellSize > 0) || w.rows === 0 || w.cols === 0) throw new Error('a welcome with an empty grid');
  w.cells = r.u32s(w.rows * w.cols);
  for (const c of w.cells) if (c !== kNoCell && c >= w.cellCount) throw new Error(`a welcome naming cell ${c} of ${w.cellCount}`);
  r.end();
  return w;
}

export function parseCatalog(view) {
  const r = new Reader(view, 'catalog');
  const n = r.u32();
  const colors = new Uint32Array(n), boxes = new Float32Array(6 * n);
  for (let i = 0; i < n; ++i) {
    colors[i] = r.u32();
    for (let k = 0; k < 6; ++k) boxes[6 * i + k] = r.f32();
  }
  r.end();
  return { colors, boxes };
}

export const kMaxCellsPerFetch = 64;

export function parseRows(view, cellCount) {
  const r = new Reader(view, 'rows');
  const sequence = r.u32(), n = r.u32(), rows = [];
  if (n > kMaxCellsPerFetch) throw new Error(`rows: ${n} rows in one reply`);
  for (let i = 0; i < n; ++i) {
    const cell = r.u32();
    if (cell >= cellCount) throw new Error(`rows: cell ${cell} of ${cellCount}`);
    const ids = r.u32s(r.u32());
    for (let k = 1; k < ids.length; ++k) if (ids[k] < ids[k - 1]) throw new Error('rows: a row is not sorted');
    rows.push({ cell, ids });
  }
  r.end();
  return { sequence, rows };
}

export function parseObject(view) {
  const r = new Reader(view, 'object');
  const o = { sequence: r.u32(), id: r.u32(), level: r.u32() };
  o.bytes = r.bytes(r.u32());
  r.end();
  return o;
}

export function parseDone(view) {
  const r = new Reader(view, 'done');
  const d = { sequence: r.u32(), objects: r.u32() };
  r.end();
  return d;
}

export function parseError(view) {
  const r = new Reader(view, 'error');
  return new TextDecoder().decode(r.bytes(r.u32()));
}
