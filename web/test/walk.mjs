// Walks a recorded path in the browser client, in Debian's Chromium driven by playwright-core
// (no browser is downloaded), and writes what it saw for `cellwalk compare --captured`:
//   node web/test/walk.mjs --url http://127.0.0.1:PORT/ --path FILE --out DIR
//        [--every 10] [--width 640] [--height 480] [--budget MiB] [--prefetch pbnp|snp] [--timeout s]
// DIR gets frameN.rgba (RGBA8, rows bottom-up as OpenGL reads them) and frameN.ids (u32 per pixel, id + 1, 0 for
// the background) for every --every-th frame, captured.json (the frames, the walk's figures)
// and browser.png (the page, overlay included). Exit 77 (a skip to ctest) when Chromium cannot start.
import { chromium } from 'playwright-core';
import fs from 'node:fs';
import path from 'node:path';

function args() {
  const a = { every: 10, width: 640, height: 480, budget: 256, prefetch: 'pbnp', timeout: 300 };
  const argv = process.argv.slice(2);
  for (let i = 0; i < argv.length; i += 2) {
    const name = argv[i].replace(/^--/, ''), value = argv[i + 1];
    if (!(name in a) && !['url', 'path', 'out'].includes(name)) throw new Error(`walk.mjs: unknown option --${name}`);
    if (value === undefined) throw new Error(`walk.mjs: --${name} needs a value`);
    a[name] = typeof a[name] === 'number' ? Number(value) : value;
  }
  for (const required of ['url', 'path', 'out']) if (!a[required]) throw new Error(`walk.mjs: --${required} is required`);
  return a;
}

// The path file (docs/paths.md): `time x y z yaw pitch` per line after `#` lines.
function readPath(file) {
  const lines = fs.readFileSync(file, 'utf8').split('\n');
  if (lines[0].trim() !== '# cellwalk path 1') throw new Error(`${file}: not a cellwalk path (its first line must be "# cellwalk path 1")`);
  return lines.filter((l) => l.trim() && !l.startsWith('#')).map((l, n) => {
    const v = l.trim().split(/\s+/).map(Number);
    if (v.length !== 6 || v.some((x) => !Number.isFinite(x))) throw new Error(`${file}: frame ${n}: expected "time x y z yaw pitch"`);
    return { time: v[0], x: v[1], y: v[2], z: v[3], yaw: v[4], pitch: v[5] };
  });
}

const a = args();
const frames = readPath(a.path);
fs.mkdirSync(a.out, { recursive: true });
let browser;
try {
  browser = await chromium.launch({
    executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium',
    args: ['--no-sandbox', '--disable-gpu-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--disable-background-networking',
           '--disable-component-update', '--disable-sync', '--no-first-run', '--disable-quic', '--ignore-gpu-blocklist'],
  });
} catch (e) {
  console.error(`walk.mjs: Chromium cannot start (${e.message.split('\n')[0]}); install Debian's chromium (scripts/setup)`);
  process.exit(77);
}
try {
  const page = await browser.newPage({ viewport: { width: a.width, height: a.height } });
  const problems = [];
  page.on('pageerror', (e) => problems.push(e.message));
  page.on('console', (m) => { if (m.type() === 'error') problems.push(m.text()); });
  const captured = [];
  await page.exposeFunction('cellwalkSave', (index, color, ids) => {
    fs.writeFileSync(path.join(a.out, `frame${index}.rgba`), Buffer.from(color, 'base64'));
    fs.writeFileSync(path.join(a.out, `frame${index}.ids`), Buffer.from(ids, 'base64'));
    captured.push(index);
  });
  const query = `?width=${a.width}&height=${a.height}&budget=${a.budget}&prefetch=${a.prefetch}`;
  // Every wait is bounded: a page that neither finishes nor fails is a failure after --timeout s.
  page.setDefaultTimeout(a.timeout * 1000);
  const bounded = (promise, what) => Promise.race([promise, new Promise((_, reject) =>
    setTimeout(() => reject(new Error(`${what} took more than ${a.timeout} s`)), a.timeout * 1000).unref())]);
  await page.goto(new URL(query, a.url).href);
  await bounded(page.evaluate(() => window.cellwalk.ready), 'the page\'s start')
    .catch((e) => { throw new Error(`the page did not start: ${e.message}; ${problems.join('; ')}`); });
  const result = await bounded(page.evaluate(({ frames, every }) =>
    window.cellwalk.walk(frames, { captureEvery: every, save: (i, c, d) => window.cellwalkSave(i, c, d) }), { frames, every: a.every }), 'the walk');
  await page.screenshot({ path: path.join(a.out, 'browser.png') });
  if (problems.length) throw new Error(`the page reported: ${problems.join('; ')}`);
  const summary = { width: a.width, height: a.height, path: path.resolve(a.path), frames: captured.sort((x, y) => x - y), walk: result };
  fs.writeFileSync(path.join(a.out, 'captured.json'), JSON.stringify(summary, null, 1) + '\n');
  const mean = (xs) => xs.reduce((s, x) => s + x, 0) / Math.max(1, xs.length);
  console.log(`walk.mjs: ${result.frames} frames, ${result.stallFrames} stalls, start-up ${result.startupMs.toFixed(0)} ms, ` +
              `draw ${mean(result.drawMs).toFixed(1)} ms, peak resident ${(result.peakResidentBytes / 1048576).toFixed(1)} of ` +
              `${(result.budgetBytes / 1048576).toFixed(0)} MiB, ${captured.length} frames captured`);
} finally {
  await browser.close();
}
