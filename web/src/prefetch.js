// Zheng's PVS prefetch on the server's grid of view cells (seed 004, ch. 7, §7.2 and §7.4;
// digest §3.10–3.11), as src/systems/pvs_stream/pvs_prefetch.cpp and pvs_cache.cpp do it:
// SNP (the cell and its 8 neighbours) and PBNP (h(R) of Table 7.1 for the region of the cell
// the viewer stands in), and §7.4's choice of the row to replace.
import { kNoCell } from './protocol.js';

// Rows grow southward (+z), columns eastward (+x); cells own their low edges.
export class ViewcellGrid {
  constructor(welcome) {
    Object.assign(this, { originX: welcome.originX, originZ: welcome.originZ, size: welcome.cellSize,
                          rows: welcome.rows, cols: welcome.cols, cells: welcome.cells });
  }
  cellAt(x, z) { return { row: Math.floor((z - this.originZ) / this.size), col: Math.floor((x - this.originX) / this.size) }; }
  contains(c) { return c.row >= 0 && c.row < this.rows && c.col >= 0 && c.col < this.cols && this.cells[c.row * this.cols + c.col] !== kNoCell; }
  // The view cell's id (its visible set's), or kNoCell.
  id(c) { return c.row >= 0 && c.row < this.rows && c.col >= 0 && c.col < this.cols ? this.cells[c.row * this.cols + c.col] : kNoCell; }
  // -1, 0, 1 along each axis: which band of the cell (x, z) lies in (Figure 7.2).
  regionAt(x, z, band) {
    const u = (x - this.originX) / this.size, v = (z - this.originZ) / this.size;
    const fu = u - Math.floor(u), fv = v - Math.floor(v);
    return { ew: fu < band ? -1 : fu >= 1 - band ? 1 : 0, ns: fv < band ? -1 : fv >= 1 - band ? 1 : 0 };
  }
}

export const chebyshev = (a, b) => Math.max(Math.abs(a.row - b.row), Math.abs(a.col - b.col));
const same = (a, b) => a.row === b.row && a.col === b.col;

// Table 7.1: h(R) is the cell, the neighbour across each band the viewer is in, and the corner
// neighbour where two bands meet. SNP: the 3 × 3 block. Missing cells are left out.
export function prefetchingArea(algorithm, grid, cell, region) {
  const offsets = [[0, 0]];
  if (algorithm === 'snp') {
    for (let dr = -1; dr <= 1; ++dr) for (let dc = -1; dc <= 1; ++dc) if (dr || dc) offsets.push([dr, dc]);
  } else {
    if (region.ns) offsets.push([region.ns, 0]);
    if (region.ew) offsets.push([0, region.ew]);
    if (region.ns && region.ew) offsets.push([region.ns, region.ew]);
  }
  return offsets.map(([dr, dc]) => ({ row: cell.row + dr, col: cell.col + dc })).filter((c) => grid.contains(c));
}

// §7.4: never a row of the area; the farthest row that is no neighbour of the viewer (the oldest
// among equals), else the oldest outside the area; -1 when every row is in the area.
export function replacementVictim(cells, area, current) {
  const inArea = (c) => area.some((a) => same(a, c));
  let victim = -1, distance = 0;
  cells.forEach((c, i) => {
    if (inArea(c)) return;
    const d = chebyshev(c, current);
    if (d > distance) { victim = i; distance = d; }
  });
  if (victim >= 0 && distance > 1) return victim;
  return cells.findIndex((c) => !inArea(c));
}
