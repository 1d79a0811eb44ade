// The browser's PVS streaming client (seed 004, ch. 7, §7.3–7.4 over a WebSocket; digest
// §3.10–3.11), the page's counterpart of src/systems/pvs_stream_client: at most `entries` rows
// of visible sets and the objects of their union, one transaction at a time (the rows of the
// prefetching area it lacks, and only the objects it does not hold, in one round trip), the
// objects it deleted named in its next fetch. A hard budget bounds the decoded geometry it
// holds: an object that does not fit after rows outside the viewer's cell are given up is
// refused (and named as dropped, so the server's mirror stays true).
import * as protocol from './protocol.js';
import { ViewcellGrid, prefetchingArea, replacementVictim } from './prefetch.js';
import { decodeMesh, ready as decoderReady } from './mesh_codec.js';

const key = (c) => `${c.row},${c.col}`;

export class StreamClient {
  // options: { budgetBytes, prefetch: 'pbnp' | 'snp', band, entries, level, onObject(id, mesh), onDrop(id) }
  constructor(url, options) {
    this.url = url;
    this.options = Object.assign({ budgetBytes: 256 << 20, prefetch: 'pbnp', band: 0.25, entries: 9, level: 0 }, options);
    this.rows = new Map();      // cell key → { cell, ids: Uint32Array }, in the order cached (oldest first)
    this.held = new Map();      // object id → decoded bytes
    this.refused = new Set();   // objects sent that the budget could not hold
    this.dropped = [];          // deleted since the last fetch (§7.4's ΔS_d)
    this.inFlight = null;       // { sequence, cells: Set of keys, started }
    this.area = [];
    this.sequence = 0;
    this.stats = { transactions: 0, rowsReceived: 0, objectsReceived: 0, objectsDropped: 0, bytesReceived: 0,
                   resident: 0, peakResident: 0, refusedObjects: 0, transactionMsMax: 0, transactionMsSum: 0 };
    this.failure = null;
  }

  async connect() {
    await decoderReady;
    this.ws = new WebSocket(this.url);
    this.ws.binaryType = 'arraybuffer';
    await new Promise((resolve, reject) => {
      this.ws.onopen = resolve;
      this.ws.onerror = () => reject(new Error(`cannot reach ${this.url}: is \`cellwalk serve --web\` running?`));
    });
    const welcomed = new Promise((resolve) => { this.onWelcome = resolve; });
    const catalogued = new Promise((resolve) => { this.onCatalog = resolve; });
    this.ws.onmessage = (event) => this.receive(event.data);
    this.ws.onclose = () => { if (!this.failure) this.failure = 'the server closed the connection'; };
    this.ws.send(protocol.hello());
    this.ws.send(protocol.catalogRequest());
    this.welcome = await welcomed;
    this.grid = new ViewcellGrid(this.welcome);
    this.catalog = await catalogued;
  }

  receive(data) {
    try {
      this.stats.bytesReceived += data.byteLength;
      const { type, payload } = protocol.parseFrame(data);
      switch (type) {
        case protocol.Message.welcome: return this.onWelcome(protocol.parseWelcome(payload));
        case protocol.Message.catalog: return this.onCatalog(protocol.parseCatalog(payload));
        case protocol.Message.rows: return this.receiveRows(protocol.parseRows(payload));
        case protocol.Message.object: return this.receiveObject(protocol.parseObject(payload));
        case protocol.Message.done: return this.finishTransaction(protocol.parseDone(payload));
        case protocol.Message.error: throw new Error(`the server refused: ${protocol.parseError(payload)}`);
        default: throw new Error(`an unexpected message type ${type}`);
      }
    } catch (e) {
      this.failure = e.message;
      this.ws.close();
    }
  }

  // Called every frame with the viewer's position: starts a transaction for the rows of the
  // prefetching area the client lacks, when none is in flight.
  update(x, z) {
    const cell = this.grid.cellAt(x, z);
    this.current = cell;
    const region = this.grid.regionAt(x, z, this.options.band);
    const area = prefetchingArea(this.options.prefetch, this.grid, cell, region);
    if (area.map(key).join(';') !== this.area.map(key).join(';')) this.area = area;
    if (this.inFlight || this.failure) return;
    const wanted = this.area.filter((c) => !this.rows.has(key(c)));
    if (wanted.length === 0) return;
    const cells = wanted.map((c) => this.grid.id(c));
    this.inFlight = { sequence: this.sequence, cells: new Set(wanted.map(key)), started: performance.now() };
    this.ws.send(protocol.fetchRequest(this.sequence++, this.options.level, cells, this.dropped));
    this.dropped = [];
    this.stats.transactions++;
  }

  receiveRows(reply) {
    for (const { cell, ids } of reply.rows) {
      const at = this.cellOfId(cell);
      this.rows.delete(key(at));
      this.rows.set(key(at), { cell: at, ids });
      this.stats.rowsReceived++;
    }
  }

  cellOfId(id) {
    const index = this.grid.cells.indexOf(id);
    if (index < 0) throw new Error(`a row for cell ${id}, which is not on the grid`);
    return { row: Math.floor(index / this.grid.cols), col: index % this.grid.cols };
  }

  receiveObject(o) {
    this.stats.objectsReceived++;
    if (o.id >= this.catalog.colors.length) throw new Error(`object ${o.id} is not in the catalog`);
    const mesh = decodeMesh(o.bytes, `object ${o.id} level ${o.level}`);
    if (!this.makeRoom(mesh.bytes)) {
      this.refused.add(o.id);
      this.dropped.push(o.id);  // the server counts it held: tell it otherwise
      this.stats.refusedObjects++;
      return;
    }
    this.refused.delete(o.id);
    this.held.set(o.id, mesh.bytes);
    this.charge(mesh.bytes);
    this.options.onObject?.(o.id, mesh);
  }

  charge(bytes) {
    this.stats.resident += bytes;
    this.stats.peakResident = Math.max(this.stats.peakResident, this.stats.resident);
  }

  // Frees rows until `bytes` more fit: rows outside the prefetching area first (§7.4's order),
  // then the area's rows but the viewer's own. False when even that is not enough.
  makeRoom(bytes) {
    const fits = () => this.stats.resident + bytes <= this.options.budgetBytes;
    while (!fits()) {
      const cells = [...this.rows.values()].map((r) => r.cell);
      let victim = replacementVictim(cells, this.area, this.current);
      if (victim < 0) victim = cells.findIndex((c) => !(c.row === this.current.row && c.col === this.current.col));
      if (victim < 0) return false;
      this.evictRows([cells[victim]]);
    }
    return true;
  }

  finishTransaction(done) {
    if (!this.inFlight || done.sequence !== this.inFlight.sequence) throw new Error(`a done for fetch ${done.sequence}, which is not in flight`);
    const ms = performance.now() - this.inFlight.started;
    this.stats.transactionMsMax = Math.max(this.stats.transactionMsMax, ms);
    this.stats.transactionMsSum += ms;
    this.inFlight = null;
    // §7.4: at most `entries` rows, never one of the area.
    const over = [];
    const cells = [...this.rows.values()].map((r) => r.cell);
    while (cells.length - over.length > this.options.entries) {
      const kept = cells.filter((c) => !over.includes(c));
      const victim = replacementVictim(kept, this.area, this.current);
      if (victim < 0) break;
      over.push(kept[victim]);
    }
    if (over.length) this.evictRows(over);
  }

  // Deletes rows and the objects no kept row sees (ΔS_d = S_d − S_c).
  evictRows(cells) {
    for (const c of cells) this.rows.delete(key(c));
    const kept = new Set();
    for (const { ids } of this.rows.values()) for (const id of ids) kept.add(id);
    for (const [id, bytes] of this.held) {
      if (kept.has(id)) continue;
      this.held.delete(id);
      this.stats.resident -= bytes;
      this.dropped.push(id);
      this.stats.objectsDropped++;
      this.options.onDrop?.(id);
    }
    for (const id of this.refused) if (!kept.has(id)) this.refused.delete(id);
  }

  // The viewer's visible set: { ready, ids }. Not ready while its row or any of its objects has
  // not arrived (the frame would miss them); objects the budget refused never arrive.
  visibleSet(x, z) {
    const cell = this.grid.cellAt(x, z);
    if (!this.grid.contains(cell)) return { ready: true, ids: [], outside: true };
    const row = this.rows.get(key(cell));
    if (!row) return { ready: false, ids: [] };
    const inFlight = this.inFlight !== null;
    for (const id of row.ids) if (!this.held.has(id) && !(this.refused.has(id) || !inFlight)) return { ready: false, ids: row.ids };
    return { ready: true, ids: row.ids, lacking: row.ids.filter((id) => !this.held.has(id)).length };
  }
}
