// Decodes one level of an object as cellwalk's world file encodes it (docs/lod.md, "Mesh
// codec"), without the zstd layer (the server removes it for browsers): quantised positions,
// octahedral normals, colours, uvs and indices through meshoptimizer's decoders (npm
// `meshoptimizer`, the same codecs the native store uses). Mirrors src/store/mesh_codec.cpp;
// a damaged level throws Error naming the field.
import { MeshoptDecoder } from 'meshoptimizer/decoder';

const kHasNormals = 1, kHasColors = 2, kZstd = 4, kHasUvs = 8, kHasTexture = 16;
const f = Math.fround;

export const ready = MeshoptDecoder.ready;

// { positions: Float32Array, normals: Float32Array|null, colors: Uint8Array|null, indices: Uint32Array, bytes }
export function decodeMesh(bytes, where) {
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  let at = 0;
  const fail = (what) => { throw new Error(`${where}: ${what}`); };
  const need = (n) => { if (at + n > bytes.byteLength) fail('the level ends too soon'); };
  const u8 = () => { need(1); return view.getUint8(at++); };
  const u32 = () => { need(4); const v = view.getUint32(at, true); at += 4; return v; };
  const f32 = () => { need(4); const v = view.getFloat32(at, true); at += 4; return v; };
  if (u8() !== 0x43 || u8() !== 0x57 || u8() !== 0x4d || u8() !== 0x43) fail('not an encoded mesh (bad magic)');
  if (u8() !== 1) fail('unsupported mesh codec version');
  const flags = u8(), positionBits = u8(), normalBits = u8();
  const vertexCount = u32(), indexCount = u32();
  const min = [f32(), f32(), f32()], max = [f32(), f32(), f32()];
  if (flags & kZstd) fail('a zstd-compressed level (the server removes zstd for browsers: update cellwalk serve)');
  if (flags & ~(kHasNormals | kHasColors | kHasUvs | kHasTexture)) fail('unknown flags');
  if (flags & kHasTexture) {
    if (!(flags & kHasUvs)) fail('a texture without texture coordinates');
    u32();  // the texture index: textures are not drawn in the browser yet
  }
  if (positionBits < 1 || positionBits > 16 || normalBits < 2 || normalBits > 16) fail('bit counts out of range');
  if (indexCount % 3 !== 0) fail('index count is not a multiple of 3');
  for (let k = 0; k < 3; ++k) {
    const extent = max[k] - min[k];  // a damaged box: negative, NaN or infinite
    if (vertexCount > 0 && !(extent >= 0 && extent < 3.4028234663852886e38)) fail('bad bounding box');
  }
  if (vertexCount * 40 + indexCount * 4 > (1 << 30)) fail('mesh larger than the decode limit');

  const stream = (what) => {
    const n = u32();
    if (n === 0) fail(`empty ${what} stream`);
    need(n);
    const s = bytes.subarray(at, at + n);
    at += n;
    return s;
  };
  const vertices = (what, size) => {
    const out = new Uint8Array(vertexCount * size);
    try { MeshoptDecoder.decodeVertexBuffer(out, vertexCount, size, stream(what)); } catch (e) { fail(`damaged ${what} (${e.message})`); }
    return out;
  };

  // Positions: {u16 x, y, z, pad}; the top step is the box's max exactly, as the native decoder.
  const q = new Uint16Array(vertices('positions', 8).buffer);
  const steps = f((1 << positionBits) - 1);
  const step = [0, 1, 2].map((k) => f(f(max[k] - min[k]) / steps));
  const positions = new Float32Array(vertexCount * 3);
  for (let i = 0; i < vertexCount; ++i)
    for (let k = 0; k < 3; ++k) {
      const v = Math.min(q[4 * i + k], steps);
      positions[3 * i + k] = v === steps ? max[k] : f(min[k] + f(v * step[k]));
    }

  let normals = null;
  if (flags & kHasNormals) {
    const size = normalBits <= 8 ? 4 : 8;
    const raw = vertices('normals', size);
    const packed = size === 4 ? new Int8Array(raw.buffer) : new Int16Array(raw.buffer);
    const top = (1 << (normalBits - 1)) - 1;
    normals = new Float32Array(vertexCount * 3);
    for (let i = 0; i < vertexCount; ++i) {
      let x = Math.max(-1, Math.min(1, packed[4 * i] / top));
      let y = Math.max(-1, Math.min(1, packed[4 * i + 1] / top));
      const z = 1 - Math.abs(x) - Math.abs(y);
      const t = Math.max(-z, 0);
      x += x >= 0 ? -t : t;
      y += y >= 0 ? -t : t;
      const l = Math.hypot(x, y, z);
      normals[3 * i] = x / l; normals[3 * i + 1] = y / l; normals[3 * i + 2] = z / l;
    }
  }
  const colors = flags & kHasColors ? vertices('colors', 4) : null;
  if (flags & kHasUvs) vertices('texture coordinates', 8);

  const indices = new Uint32Array(indexCount);
  try {
    MeshoptDecoder.decodeIndexBuffer(new Uint8Array(indices.buffer), indexCount, 4, stream('indices'));
  } catch (e) { fail(`damaged indices (${e.message})`); }
  for (let i = 0; i < indexCount; ++i) if (indices[i] >= vertexCount) fail('index out of range');
  if (at !== bytes.byteLength) fail('trailing bytes after the index stream');
  const resident = positions.byteLength + (normals ? normals.byteLength : 0) + (colors ? colors.byteLength : 0) + indices.byteLength;
  return { positions, normals, colors, indices, bytes: resident };
}
