// cellwalk's camera and lens in the page, as src/core/camera.cpp makes them: yaw and pitch in
// degrees (yaw 0 looks along −Z, yaw 90 along −X, pitch up positive), glm's lookAt and
// perspective (right-handed, clip z in [−1, 1]), column-major. The same matrices the native
// renderer uses, so the browser's frames can be compared with its pixel for pixel.

export const lens = { fovYDeg: 60, near: 0.25, far: 5000 };

// Every step in single precision, in glm's order, so that the matrices are the native ones to
// the bit or nearly (a sliver of a pixel rasterises the same only from the same vertices).
const f = Math.fround;
const rad = (d) => f(f(d) * f(0.01745329251994329576923690768489));
const sub = (a, b) => [f(a[0] - b[0]), f(a[1] - b[1]), f(a[2] - b[2])];
const add = (a, b) => [f(a[0] + b[0]), f(a[1] + b[1]), f(a[2] + b[2])];
const cross = (a, b) => [f(f(a[1] * b[2]) - f(a[2] * b[1])), f(f(a[2] * b[0]) - f(a[0] * b[2])), f(f(a[0] * b[1]) - f(a[1] * b[0]))];
const dot = (a, b) => f(f(f(a[0] * b[0]) + f(a[1] * b[1])) + f(a[2] * b[2]));
const normalize = (a) => { const k = f(1 / f(Math.sqrt(dot(a, a)))); return [f(a[0] * k), f(a[1] * k), f(a[2] * k)]; };

export function forward(yawDeg, pitchDeg) {
  const y = rad(yawDeg), p = rad(pitchDeg);
  const cp = f(Math.cos(p));
  return [f(-f(Math.sin(y)) * cp), f(Math.sin(p)), f(-f(Math.cos(y)) * cp)];
}

// Column-major 4 × 4 (m[col * 4 + row]); glm's order of sums.
function multiply(a, b) {
  const out = new Float32Array(16);
  for (let c = 0; c < 4; ++c) for (let r = 0; r < 4; ++r) {
    let s = f(a[r] * b[c * 4]);
    for (let k = 1; k < 4; ++k) s = f(s + f(a[k * 4 + r] * b[c * 4 + k]));
    out[c * 4 + r] = s;
  }
  return out;
}

export function viewProjection(eyeIn, yawDeg, pitchDeg, aspect, l = lens) {
  const eye = eyeIn.map(f);
  const f0 = forward(yawDeg, pitchDeg);
  const yaw = rad(yawDeg);
  const right = [f(Math.cos(yaw)), 0, f(-f(Math.sin(yaw)))];
  const up = cross(right, f0);
  const fw = normalize(sub(add(eye, f0), eye)), s = normalize(cross(fw, up)), u = cross(s, fw);
  const view = new Float32Array([s[0], u[0], -fw[0], 0, s[1], u[1], -fw[1], 0, s[2], u[2], -fw[2], 0,
                                 -dot(s, eye), -dot(u, eye), dot(fw, eye), 1]);
  const t = f(Math.tan(f(rad(l.fovYDeg) / 2)));
  const near = f(l.near), far = f(l.far), asp = f(aspect);
  const proj = new Float32Array(16);
  proj[0] = f(1 / f(asp * t));
  proj[5] = f(1 / t);
  proj[10] = f(-f(far + near) / f(far - near));
  proj[11] = -1;
  proj[14] = f(-f(f(f(2 * far) * near)) / f(far - near));
  return multiply(proj, view);
}

// Gribb & Hartmann's six planes of a view-projection, normals inwards.
export function frustumPlanes(m) {
  const row = (r) => [m[r], m[4 + r], m[8 + r], m[12 + r]];
  const w = row(3), planes = [];
  for (let r = 0; r < 3; ++r) {
    const x = row(r);
    planes.push(w.map((v, i) => v + x[i]), w.map((v, i) => v - x[i]));
  }
  return planes;
}

// Conservative: false only when the box lies wholly outside one plane.
export function boxInFrustum(planes, box, at) {
  for (const p of planes) {
    const x = p[0] >= 0 ? box[at + 3] : box[at], y = p[1] >= 0 ? box[at + 4] : box[at + 1], z = p[2] >= 0 ? box[at + 5] : box[at + 2];
    if (p[0] * x + p[1] * y + p[2] * z + p[3] < 0) return false;
  }
  return true;
}
