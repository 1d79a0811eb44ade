// Draws the streamed objects with three.js (WebGL2), shaded exactly as cellwalk's native
// renderer shades them (src/render/shaders.hpp: one directional light plus ambient, two-sided,
// the sky-and-ground backdrop), so that a browser frame can be compared with a native one; an id
// pass writes object id + 1 as four bytes per pixel, as the native id buffer holds it.
import * as THREE from 'three';
import { viewProjection, frustumPlanes, boxInFrustum } from './view.js';

const kBackground = [178 / 255, 204 / 255, 230 / 255];

// The GLSL below is src/render/shaders.hpp's, in GLSL ES 3.00: a change there is made here too
// (tests/web_walk_test.sh compares the two renderers' frames and fails when they part).
const meshVertex = `precision highp float; precision highp int;
in vec3 position; in vec3 normal; in vec4 a_color;
uniform mat4 u_view_projection; uniform vec4 u_color; uniform int u_has_colors;
out vec3 v_position; out vec3 v_normal; out vec4 v_color;
void main() {
  gl_Position = u_view_projection * vec4(position, 1.0);
  v_position = position; v_normal = normal;
  v_color = u_has_colors != 0 ? a_color : u_color;
}`;

const meshFragment = `precision highp float; precision highp int;
uniform vec3 u_eye_position;
in vec3 v_position; in vec3 v_normal; in vec4 v_color;
out vec4 o_color;
const vec3 kLightDirection = normalize(vec3(0.4, 1.0, 0.3));
const float kAmbient = 0.35;
void main() {
  float length_squared = dot(v_normal, v_normal);
  vec3 n = length_squared > 0.0 ? v_normal * inversesqrt(length_squared) : vec3(0.0);
  if (dot(n, u_eye_position - v_position) < 0.0) n = -n;
  float light = kAmbient + (1.0 - kAmbient) * max(dot(n, kLightDirection), 0.0);
  o_color = vec4(v_color.rgb * light, 1.0);
}`;

const idFragment = `precision highp float; precision highp int;
uniform uint u_object_id;
out vec4 o_color;
void main() {
  uint id = u_object_id;
  o_color = vec4(float(id & 255u), float((id >> 8) & 255u), float((id >> 16) & 255u), float(id >> 24)) / 255.0;
}`;

const backdropVertex = `precision highp float;
in vec3 position; out vec2 v_ndc;
void main() { v_ndc = position.xy; gl_Position = vec4(position.xy, 1.0, 1.0); }`;

const backdropFragment = `precision highp float;
uniform mat4 u_inverse_view_projection; uniform vec3 u_eye; uniform vec3 u_sky; uniform vec3 u_ground;
in vec2 v_ndc; out vec4 o_color;
void main() {
  vec4 near_point = u_inverse_view_projection * vec4(v_ndc, -1.0, 1.0);
  vec4 far_point = u_inverse_view_projection * vec4(v_ndc, 1.0, 1.0);
  vec3 dir = normalize(far_point.xyz / far_point.w - near_point.xyz / near_point.w);
  float height = u_eye.y - u_ground.x;
  if (dir.y >= 0.0 || height <= 0.0) {
    vec3 zenith = vec3(0.36, 0.55, 0.85);
    o_color = vec4(mix(u_sky, zenith, sqrt(max(dir.y, 0.0))), 1.0);
    return;
  }
  vec3 ground = u_eye + dir * (height / -dir.y);
  vec2 cell = abs(fract(ground.xz / u_ground.y) - 0.5);
  float line = step(0.48, max(cell.x, cell.y));
  float haze = clamp(length(ground - u_eye) / u_ground.z, 0.0, 1.0);
  vec3 earth = mix(vec3(0.42, 0.44, 0.40), vec3(0.34, 0.36, 0.33), line);
  o_color = vec4(mix(earth, u_sky, haze), 1.0);
}`;

export class Renderer {
  // catalog: { colors, boxes } of every object (protocol.js).
  constructor(canvas, width, height, catalog) {
    this.gl = new THREE.WebGLRenderer({ canvas, antialias: false, alpha: false, powerPreference: 'high-performance' });
    this.gl.setPixelRatio(1);
    this.gl.setSize(width, height, false);
    this.gl.autoClear = true;
    this.gl.setClearColor(new THREE.Color().setRGB(...kBackground, THREE.LinearSRGBColorSpace), 1);
    this.width = width;
    this.height = height;
    this.catalog = catalog;
    this.scene = new THREE.Scene();
    this.camera = new THREE.Camera();  // unused: the matrices are cellwalk's, set as uniforms
    this.meshes = new Map();
    this.viewProjection = new THREE.Matrix4();
    this.eye = new THREE.Vector3();
    const shared = { u_view_projection: { value: this.viewProjection }, u_eye_position: { value: this.eye } };
    this.colorMaterial = new THREE.RawShaderMaterial({
      glslVersion: THREE.GLSL3, vertexShader: meshVertex, fragmentShader: meshFragment, side: THREE.DoubleSide,
      uniforms: { ...shared, u_color: { value: new THREE.Vector4() }, u_has_colors: { value: 0 } } });
    this.idMaterial = new THREE.RawShaderMaterial({
      glslVersion: THREE.GLSL3, vertexShader: meshVertex, fragmentShader: idFragment, side: THREE.DoubleSide,
      uniforms: { ...shared, u_color: { value: new THREE.Vector4() }, u_has_colors: { value: 0 }, u_object_id: { value: 0 } } });
    this.backdrop = this.makeBackdrop(catalog);
    this.scene.add(this.backdrop);
  }

  makeBackdrop(catalog) {
    // The ground at the world's lowest point, its grid and haze fitted to its extent (fit_backdrop).
    const b = catalog.boxes, min = [Infinity, Infinity, Infinity], max = [-Infinity, -Infinity, -Infinity];
    for (let i = 0; i < b.length; i += 6) for (let k = 0; k < 3; ++k) { min[k] = Math.min(min[k], b[i + k]); max[k] = Math.max(max[k], b[i + 3 + k]); }
    const extent = Math.max(max[0] - min[0], max[2] - min[2], 1e-3);
    const grid = Math.min(10, Math.pow(10, Math.round(Math.log10(extent / 10))));
    this.worldMin = min; this.worldMax = max;
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array([-1, -1, 0, 3, -1, 0, -1, 3, 0]), 3));
    this.inverse = new THREE.Matrix4();
    const material = new THREE.RawShaderMaterial({
      glslVersion: THREE.GLSL3, vertexShader: backdropVertex, fragmentShader: backdropFragment, depthTest: false, depthWrite: false,
      uniforms: { u_inverse_view_projection: { value: this.inverse }, u_eye: { value: this.eye },
                  u_sky: { value: new THREE.Vector3(...kBackground) }, u_ground: { value: new THREE.Vector3(min[1], grid, 30 * extent) } } });
    const mesh = new THREE.Mesh(geometry, material);
    mesh.frustumCulled = false;
    mesh.renderOrder = -1;
    return mesh;
  }

  add(id, decoded) {
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(decoded.positions, 3));
    // No normals: the attribute is left out and reads (0, 0, 0), lit by the ambient term alone,
    // as the native renderer draws such a mesh.
    if (decoded.normals) geometry.setAttribute('normal', new THREE.BufferAttribute(decoded.normals, 3));
    if (decoded.colors) geometry.setAttribute('a_color', new THREE.BufferAttribute(decoded.colors, 4, true));
    geometry.setIndex(new THREE.BufferAttribute(decoded.indices, 1));
    const mesh = new THREE.Mesh(geometry, this.colorMaterial);
    mesh.frustumCulled = false;
    mesh.visible = false;
    const c = this.catalog.colors[id];
    const color = new THREE.Vector4((c & 255) / 255, ((c >>> 8) & 255) / 255, ((c >>> 16) & 255) / 255, (c >>> 24) / 255);
    const hasColors = decoded.colors ? 1 : 0;
    mesh.onBeforeRender = (renderer, scene, camera, g, material) => {
      material.uniforms.u_color.value.copy(color);
      material.uniforms.u_has_colors.value = hasColors;
      if (material.uniforms.u_object_id) material.uniforms.u_object_id.value = id + 1;
      material.uniformsNeedUpdate = true;
    };
    this.scene.add(mesh);
    this.meshes.set(id, mesh);
  }

  // The bytes of every array the meshes hold (positions, normals, colours, indices): the same
  // geometry as the stream client's count, summed apart from it.
  geometryBytes() {
    let bytes = 0;
    for (const mesh of this.meshes.values()) {
      for (const attribute of Object.values(mesh.geometry.attributes)) bytes += attribute.array.byteLength;
      bytes += mesh.geometry.index.array.byteLength;
    }
    return bytes;
  }

  remove(id) {
    const mesh = this.meshes.get(id);
    if (!mesh) return;
    this.scene.remove(mesh);
    mesh.geometry.dispose();
    this.meshes.delete(id);
  }

  // Draws `ids` (those held) seen from the camera, culled to the view frustum; returns how many
  // objects and triangles were drawn. target: null for the canvas, or a render target.
  draw(camera, ids, { target = null, pass = 'color', backdrop = true } = {}) {
    const m = viewProjection(camera.position, camera.yaw, camera.pitch, this.width / this.height);
    this.viewProjection.fromArray(m);
    this.inverse.copy(this.viewProjection).invert();
    this.eye.set(...camera.position);
    const planes = frustumPlanes(m);
    for (const mesh of this.meshes.values()) mesh.visible = false;
    let objects = 0, triangles = 0;
    const material = pass === 'ids' ? this.idMaterial : this.colorMaterial;
    for (const id of ids) {
      const mesh = this.meshes.get(id);
      if (!mesh || !boxInFrustum(planes, this.catalog.boxes, 6 * id)) continue;
      mesh.visible = true;
      mesh.material = material;
      objects++;
      triangles += mesh.geometry.index.count / 3;
    }
    this.backdrop.visible = backdrop && pass === 'color';
    if (pass === 'ids') this.gl.setClearColor(0x000000, 0);
    this.gl.setRenderTarget(target);
    this.gl.render(this.scene, this.camera);
    this.gl.setRenderTarget(null);
    if (pass === 'ids') this.gl.setClearColor(new THREE.Color().setRGB(...kBackground, THREE.LinearSRGBColorSpace), 1);
    return { objects, triangles };
  }

  // Returns when the GPU has drawn what was asked of it. gl.finish() does not wait for that in
  // Chromium (the GPU process may still be rasterising); reading a pixel back does.
  waitForGpu() {
    const gl = this.gl.getContext();
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, this.pixel ??= new Uint8Array(4));
  }

  // The frame as the native renderer's images: RGBA8 colour and u32 ids, rows bottom-up as
  // OpenGL reads them (render/image.hpp).
  capture(camera, ids) {
    // 32-bit float depth, as the native renderer's (the canvas has 24 bits: coplanar faces far
    // away would resolve otherwise).
    const target = new THREE.WebGLRenderTarget(this.width, this.height, {
      type: THREE.UnsignedByteType, depthBuffer: true, depthTexture: new THREE.DepthTexture(this.width, this.height, THREE.FloatType) });
    const read = () => {
      const out = new Uint8Array(this.width * this.height * 4);
      this.gl.readRenderTargetPixels(target, 0, 0, this.width, this.height, out);
      return out;
    };
    this.draw(camera, ids, { target, pass: 'color' });
    const color = read();
    this.draw(camera, ids, { target, pass: 'ids' });
    const idBytes = read();
    target.depthTexture.dispose();
    target.dispose();
    return { color, ids: idBytes };
  }
}
