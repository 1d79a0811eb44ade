// The checks of tests/web_walk_test.sh on what walk.mjs and `cellwalk compare --captured` wrote.
//   full CAPTURED.json FIDELITY.json: every frame drawn with its cell's set, none late; the
//     page's resident geometry within its budget; no visible object missed but slivers of at
//     most 2 pixels; the image within 35 dB PSNR of the native render.
//   tight CAPTURED.json: a budget too small for the city is held, objects refused to hold it.
import fs from 'node:fs';

const [mode, capturedFile, fidelityFile] = process.argv.slice(2);
const captured = JSON.parse(fs.readFileSync(capturedFile, 'utf8'));
const walk = captured.walk;
const failures = [];
const expect = (ok, what) => { if (!ok) failures.push(what); };

expect(walk.peakResidentBytes <= walk.budgetBytes, `peak resident ${walk.peakResidentBytes} B over the budget of ${walk.budgetBytes} B`);
// Apart from the client's own count: the arrays the drawn meshes hold, summed every frame.
expect(walk.peakGeometryBytes > 0 && walk.peakGeometryBytes <= walk.budgetBytes,
       `the meshes held ${walk.peakGeometryBytes} B at the most, against a budget of ${walk.budgetBytes} B`);
expect(walk.lateFrames === 0, `${walk.lateFrames} frames drawn without their cell's visible set`);
if (mode === 'full') {
  const f = JSON.parse(fs.readFileSync(fidelityFile, 'utf8'));
  expect(f.frames === captured.frames.length && f.frames >= 5, `${f.frames} frames compared`);
  expect(walk.refusedObjects === 0 && walk.lackingObjects === 0, `${walk.refusedObjects} objects refused under a budget that holds the city`);
  expect(f.largest_missed_pixels <= 2, `a missed object covering ${f.largest_missed_pixels} pixels of the native frame`);
  expect(f.mean_psnr_db >= 35, `PSNR ${f.mean_psnr_db} dB against the native render`);
  expect(f.max_differing_fraction < 0.1, `${(100 * f.max_differing_fraction).toFixed(1)} % of a frame's pixels differ`);
  console.log(`full walk: ${walk.frames} frames, ${walk.stallFrames} stalls, peak ${walk.peakResidentBytes} of ${walk.budgetBytes} B, ` +
              `PSNR ${f.mean_psnr_db.toFixed(1)} dB, missed ${f.missed_objects} of ${f.visible_objects} (largest ${f.largest_missed_pixels} px), ` +
              `pixel error max ${f.pixel_error.max_px.toFixed(2)} px`);
} else if (mode === 'tight') {
  expect(walk.refusedObjects > 0, 'no object refused: the budget did not bind, so the test shows nothing');
  // Once the budget replaces the prefetching area's rows only the viewer's cell is asked for: a
  // fetch a frame would mean the rows given up are asked for again and again.
  expect(walk.transactions < walk.frames / 2, `${walk.transactions} transactions in ${walk.frames} frames`);
  console.log(`tight walk: peak ${walk.peakResidentBytes} of ${walk.budgetBytes} B, ${walk.refusedObjects} objects refused`);
} else {
  failures.push(`unknown mode ${mode}`);
}
if (failures.length) {
  console.error(`FAIL (${mode}): ${failures.join('; ')}`);
  process.exit(1);
}
