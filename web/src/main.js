// cellwalk in the browser (docs/web.md): connects to `cellwalk serve --web`, streams the visible
// sets and the geometry of the cells around the viewer (PBNP prefetch, a hard budget), draws
// them with three.js, and shows frame time, resident bytes and stalls. `window.cellwalk.walk`
// replays a recorded path for tests and measurements (web/test/walk.mjs).
//
// Query parameters: budget=MiB (256), prefetch=pbnp|snp, band=0.25, entries=9, level=0,
// width, height (default: the window), ws=URL (default: this server's /ws).
import * as THREE from 'three';
import { StreamClient } from './stream_client.js';
import { Renderer } from './renderer.js';
import { Walker, birdsEyeCamera } from './walker.js';

THREE.ColorManagement.enabled = false;  // colours are cellwalk's bytes, unconverted

const params = new URLSearchParams(location.search);
const number = (name, fallback) => (params.has(name) ? Number(params.get(name)) : fallback);
const overlay = document.getElementById('overlay');
const errorBox = document.getElementById('error');
const showError = (message) => { errorBox.textContent = message; errorBox.style.display = 'block'; };

const options = {
  budgetBytes: number('budget', 256) * 1024 * 1024,
  prefetch: params.get('prefetch') ?? 'pbnp',
  band: number('band', 0.25),
  entries: number('entries', 9),
  level: number('level', 0),
};
const width = number('width', window.innerWidth), height = number('height', window.innerHeight);
const url = params.get('ws') ?? `${location.protocol === 'https:' ? 'wss' : 'ws'}://${location.host}/ws`;

const mib = (b) => (b / 1048576).toFixed(1);

class App {
  async start() {
    let renderer = null;
    this.client = new StreamClient(url, {
      ...options,
      onObject: (id, mesh) => renderer.add(id, mesh),
      onDrop: (id) => renderer.remove(id),
    });
    await this.client.connect();
    const canvas = document.createElement('canvas');
    canvas.width = width;
    canvas.height = height;
    document.body.prepend(canvas);
    renderer = this.renderer = new Renderer(canvas, width, height, this.client.catalog);
    this.walker = new Walker(canvas, this.startingView());
    this.frames = { count: 0, stalls: 0, msSum: 0, last: performance.now(), drawMs: 0, started: false };
  }

  // The middle of the first view cell of the grid, at eye height over the lowest ground.
  startingView() {
    const g = this.client.grid;
    const index = g.cells.findIndex((c) => c !== 0xffffffff);
    const row = Math.floor(index / g.cols), col = index % g.cols;
    return { position: [g.originX + (col + 0.5) * g.size, this.renderer.worldMin[1] + 1.7, g.originZ + (row + 0.5) * g.size], yaw: 0, pitch: 0 };
  }

  // One frame of the interactive loop.
  tick(now) {
    const seconds = Math.min(0.1, (now - this.frames.last) / 1000);
    this.frames.last = now;
    this.walker.step(seconds);
    const camera = this.walker.camera;
    this.client.update(camera.position[0], camera.position[2]);
    const set = this.client.visibleSet(camera.position[0], camera.position[2]);
    if (set.ready) this.frames.started = true;
    else if (this.frames.started) this.frames.stalls++;
    const view = this.walker.birdsEye ? birdsEyeCamera(camera, 4 * this.client.grid.size + 60) : camera;
    const ids = this.walker.birdsEye ? [...this.client.held.keys()] : set.ids;
    const t0 = performance.now();
    const drawn = this.renderer.draw(view, ids);
    this.frames.drawMs = 0.9 * this.frames.drawMs + 0.1 * (performance.now() - t0);
    this.frames.count++;
    this.frames.msSum = 0.9 * this.frames.msSum + 0.1 * seconds * 1000;
    this.showStats(drawn, set);
  }

  showStats(drawn, set) {
    const s = this.client.stats, p = this.walker.camera.position;
    const cell = this.client.grid.cellAt(p[0], p[2]);
    overlay.textContent = [
      `frame ${this.frames.msSum.toFixed(1)} ms (draw ${this.frames.drawMs.toFixed(1)} ms)${this.walker.birdsEye ? '  [bird\'s eye]' : ''}`,
      `cell ${cell.row},${cell.col}: ${set.ids.length} visible, ${drawn.objects} drawn, ${drawn.triangles} triangles`,
      `resident ${mib(s.resident)} of ${mib(options.budgetBytes)} MiB (peak ${mib(s.peakResident)})`,
      `stalls ${this.frames.stalls}, transactions ${s.transactions}, received ${mib(s.bytesReceived)} MiB`,
      `${options.prefetch.toUpperCase()} · WASD/arrows walk, drag to look, B bird's eye`,
    ].join('\n');
    if (this.client.failure) showError(this.client.failure);
  }

  // Replays `frames` ([{time, x, y, z, yaw, pitch}]) at the path's pace; a frame whose cell's
  // visible set has not arrived waits for it (a stall, counted after the first frame). Every
  // `captureEvery`-th frame is read back and handed to `save(frameIndex, colorBase64, idsBase64)`.
  async walk(frames, { captureEvery = 0, save = null, waitMs = 10000 } = {}) {
    const nextFrame = () => new Promise((resolve) => requestAnimationFrame(resolve));
    const result = { frames: frames.length, stallFrames: 0, lateFrames: 0, startupMs: 0, drawMs: [], frameMs: [], objectsDrawn: [],
                     lackingObjects: 0, peakGeometryBytes: 0 };
    const t0 = performance.now();
    let previous = t0;
    for (let i = 0; i < frames.length; ++i) {
      const f = frames[i], camera = { position: [f.x, f.y, f.z], yaw: f.yaw, pitch: f.pitch };
      while (performance.now() - t0 < (f.time - frames[0].time) * 1000) await nextFrame();
      this.client.update(f.x, f.z);
      let set = this.client.visibleSet(f.x, f.z);
      const waitStart = performance.now();
      if (!set.ready && i > 0) result.stallFrames++;
      while (!set.ready && !this.client.failure && performance.now() - waitStart < waitMs) {
        await nextFrame();
        this.client.update(f.x, f.z);
        set = this.client.visibleSet(f.x, f.z);
      }
      if (this.client.failure) throw new Error(this.client.failure);
      if (!set.ready) result.lateFrames++;
      result.lackingObjects += set.lacking ?? 0;
      result.peakGeometryBytes = Math.max(result.peakGeometryBytes, this.renderer.geometryBytes());
      if (i === 0) result.startupMs = performance.now() - t0;
      const start = performance.now();
      const drawn = this.renderer.draw(camera, set.ids);
      this.renderer.waitForGpu();
      result.drawMs.push(performance.now() - start);
      result.objectsDrawn.push(drawn.objects);
      if (save && captureEvery > 0 && i % captureEvery === 0) {
        const image = this.renderer.capture(camera, set.ids);
        await save(i, toBase64(image.color), toBase64(image.ids));
      }
      const now = performance.now();
      result.frameMs.push(now - previous);
      previous = now;
      this.frames.last = now;
      this.walker.camera = camera;
      this.showStats(drawn, set);
      await nextFrame();
    }
    const s = this.client.stats;
    if (this.client.failure) throw new Error(this.client.failure);
    return Object.assign(result, { width, height, budgetBytes: options.budgetBytes, peakResidentBytes: s.peakResident,
                                   residentBytes: s.resident, refusedObjects: s.refusedObjects, transactions: s.transactions,
                                   bytesReceived: s.bytesReceived, objectsReceived: s.objectsReceived, objectsDropped: s.objectsDropped,
                                   transactionMsMax: s.transactionMsMax, prefetch: options.prefetch,
                                   jsHeapBytes: performance.memory ? performance.memory.usedJSHeapSize : null });
  }
}

function toBase64(bytes) {
  let s = '';
  for (let i = 0; i < bytes.length; i += 0x8000) s += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
  return btoa(s);
}

const app = new App();
window.cellwalk = {
  ready: app.start().then(() => {
    const loop = (now) => {
      if (!window.cellwalk.walking) app.tick(now);
      requestAnimationFrame(loop);
    };
    requestAnimationFrame(loop);
    return { width, height, objects: app.client.catalog.colors.length, cells: app.client.welcome.cellCount };
  }).catch((e) => { showError(e.message); throw e; }),
  walking: false,
  async walk(frames, walkOptions) {
    await window.cellwalk.ready;
    window.cellwalk.walking = true;
    try { return await app.walk(frames, walkOptions); } finally { window.cellwalk.walking = false; }
  },
  stats: () => ({ ...app.client.stats, stalls: app.frames.stalls }),
};
