// The browser's PVS streaming client (seed 004, ch. 7, §7.3–7.4 over a WebSocket; digest
// §3.10–3.11), the page's counterpart of src/systems/pvs_stream_client: at most `entries` rows
// of visible sets and the objects of their union, one transaction at a time (the rows of the
// prefetching area it lacks, and only the objects it does not hold, in one round trip), the
// objects it deleted named in its next fetch.
//
// A hard budget bounds what it holds: the rows' ids and the decoded geometry. What does not fit
// makes rows give way (§7.4's order, then the area's rows but the viewer's own); an object that
// still does not fit, or that no row it keeps sees any more, is not kept and is named dropped, so
// the server's mirror of what the page holds stays true. Once the budget has replaced a row of
// the prefetching area, only the viewer's own cell is asked for until it changes cell (asking
// again for those rows would replace them again, fetch after fetch), as the native client does.
import * as protocol from './protocol.js';
import { ViewcellGrid, prefetchingArea, replacementVictim } from './prefetch.js';
import { decodeMesh, ready as decoderReady } from './mesh_codec.js';

const key = (c) => `${c.row},${c.col}`;
const same = (a, b) => a.row === b.row && a.col === b.col;

export class StreamClient {
  // options: { budgetBytes, prefetch: 'pbnp' | 'snp', band, entries, level, onObject(id, mesh), onDrop(id) }
  constructor(url, options) {
    this.url = url;
    this.options = Object.assign({ budgetBytes: 256 << 20, prefetch: 'pbnp', band: 0.25, entries: 9, level: 0 }, options);
    this.rows = new Map();      // cell key → { cell, ids: Uint32Array }, in the order cached (oldest first)
    this.seenBy = new Map();    // object id → how many cached rows hold it
    this.held = new Map();      // object id → bytes charged for it
    this.refused = new Set();   // objects of cached rows the budget could not hold
    this.dropped = [];          // deleted since the last fetch (§7.4's ΔS_d)
    this.inFlight = null;       // { sequence, started }
    this.area = [];
    this.tight = false;
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
    // The welcome and the catalog, or the reason the session ended before them.
    const started = new Promise((resolve, reject) => {
      const parts = {};
      const settle = () => { if (parts.welcome && parts.catalog) resolve(parts); };
      this.onWelcome = (w) => { parts.welcome = w; settle(); };
      this.onCatalog = (c) => { parts.catalog = c; settle(); };
      this.onFailure = (reason) => reject(new Error(reason));
    });
    this.ws.onmessage = (event) => this.receive(event.data);
    this.ws.onclose = () => this.fail('the server closed the connection');
    this.ws.send(protocol.hello());
    this.ws.send(protocol.catalogRequest());
    const { welcome, catalog } = await started;
    this.welcome = welcome;
    this.grid = new ViewcellGrid(welcome);
    this.catalog = catalog;
  }

  fail(reason) {
    if (this.failure) return;
    this.failure = reason;
    this.onFailure?.(reason);
    this.ws.close();
  }

  receive(data) {
    try {
      this.stats.bytesReceived += data.byteLength;
      const { type, payload } = protocol.parseFrame(data);
      switch (type) {
        case protocol.Message.welcome: return this.onWelcome(protocol.parseWelcome(payload));
        case protocol.Message.catalog: return this.onCatalog(protocol.parseCatalog(payload));
        case protocol.Message.rows: return this.receiveRows(protocol.parseRows(payload, this.welcome.cellCount));
        case protocol.Message.object: return this.receiveObject(protocol.parseObject(payload));
        case protocol.Message.done: return this.finishTransaction(protocol.parseDone(payload));
        case protocol.Message.error: throw new Error(`the server refused: ${protocol.parseError(payload)}`);
        default: throw new Error(`an unexpected message type ${type}`);
      }
    } catch (e) {
      this.fail(e.message);
    }
  }

  // Called every frame with the viewer's position: starts a transaction for the rows of the
  // prefetching area the client lacks, when none is in flight.
  update(x, z) {
    const cell = this.grid.cellAt(x, z);
    if (this.current && !same(cell, this.current)) this.tight = false;
    this.current = cell;
    this.area = prefetchingArea(this.options.prefetch, this.grid, cell, this.grid.regionAt(x, z, this.options.band));
    if (this.inFlight || this.failure) return;
    const asked = this.tight ? this.area.filter((c) => same(c, cell)) : this.area;
    const wanted = asked.filter((c) => !this.rows.has(key(c)));
    if (wanted.length === 0) return;
    this.inFlight = { sequence: this.sequence, started: performance.now() };
    this.ws.send(protocol.fetchRequest(this.sequence++, this.options.level, wanted.map((c) => this.grid.id(c)), this.dropped));
    this.dropped = [];
    this.stats.transactions++;
  }

  receiveRows(reply) {
    for (const { cell, ids } of reply.rows) {
      const at = this.cellOfId(cell);
      if (this.rows.has(key(at))) this.evictRows([at]);
      if (!this.makeRoom(ids.byteLength, at)) throw new Error(`the budget of ${this.options.budgetBytes} bytes cannot hold the visible set of cell ${cell}`);
      this.rows.set(key(at), { cell: at, ids });
      for (const id of ids) this.seenBy.set(id, (this.seenBy.get(id) ?? 0) + 1);
      this.charge(ids.byteLength);
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
    if (this.held.has(o.id)) throw new Error(`object ${o.id} sent again while held`);
    const refuse = () => { this.dropped.push(o.id); };  // the server counts it held: tell it otherwise
    if (!this.seenBy.get(o.id)) return refuse();       // its rows gave way to the budget meanwhile
    const mesh = decodeMesh(o.bytes, `object ${o.id} level ${o.level}`);
    if (!this.makeRoom(mesh.bytes, this.current)) {
      this.refused.add(o.id);
      this.stats.refusedObjects++;
      return refuse();
    }
    this.held.set(o.id, mesh.bytes);
    this.charge(mesh.bytes);
    this.options.onObject?.(o.id, mesh);
  }

  charge(bytes) {
    this.stats.resident += bytes;
    this.stats.peakResident = Math.max(this.stats.peakResident, this.stats.resident);
  }

  // Frees rows until `bytes` more fit, never the row of `keep`: rows outside the prefetching
  // area first (§7.4's order), then the area's rows. False when that is not enough.
  makeRoom(bytes, keep) {
    if (bytes > this.options.budgetBytes) return false;
    while (this.stats.resident + bytes > this.options.budgetBytes) {
      const cells = [...this.rows.values()].map((r) => r.cell).filter((c) => !keep || !same(c, keep));
      let victim = replacementVictim(cells, this.area, this.current);
      if (victim < 0 && cells.length) {
        victim = 0;  // the oldest row of the area: the budget replaces the area's rows
        this.tight = true;
      }
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
    while (this.rows.size > this.options.entries) {
      const cells = [...this.rows.values()].map((r) => r.cell);
      const victim = replacementVictim(cells, this.area, this.current);
      if (victim < 0) break;
      this.evictRows([cells[victim]]);
    }
  }

  // Deletes rows and the objects no kept row sees (ΔS_d = S_d − S_c).
  evictRows(cells) {
    for (const c of cells) {
      const row = this.rows.get(key(c));
      if (!row) continue;
      this.rows.delete(key(c));
      this.stats.resident -= row.ids.byteLength;
      for (const id of row.ids) {
        const n = this.seenBy.get(id) - 1;
        if (n > 0) { this.seenBy.set(id, n); continue; }
        this.seenBy.delete(id);
        this.refused.delete(id);
        const bytes = this.held.get(id);
        if (bytes === undefined) continue;
        this.held.delete(id);
        this.stats.resident -= bytes;
        this.dropped.push(id);
        this.stats.objectsDropped++;
        this.options.onDrop?.(id);
      }
    }
  }

  // The viewer's visible set: { ready, ids, lacking }. Not ready while its row or any of its
  // objects is still to come; `lacking` counts those the budget refused.
  visibleSet(x, z) {
    const cell = this.grid.cellAt(x, z);
    if (!this.grid.contains(cell)) return { ready: true, ids: [], lacking: 0, outside: true };
    const row = this.rows.get(key(cell));
    if (!row) return { ready: false, ids: [] };
    let lacking = 0;
    for (const id of row.ids) {
      if (this.held.has(id)) continue;
      if (!this.refused.has(id)) {
        // Nothing in flight can bring it: the row is asked for again.
        if (!this.inFlight) this.evictRows([cell]);
        return { ready: false, ids: row.ids };
      }
      lacking++;
    }
    return { ready: true, ids: row.ids, lacking };
  }
}
