// Walking by hand: W A S D (or the arrows) move on the ground plane, Shift runs, dragging the
// mouse looks around, B toggles the bird's-eye view, Q and E raise and lower the eye.
import { forward } from './view.js';

export class Walker {
  constructor(element, start) {
    this.camera = { position: start.position.slice(), yaw: start.yaw, pitch: start.pitch };
    this.keys = new Set();
    this.birdsEye = false;
    window.addEventListener('keydown', (e) => {
      this.keys.add(e.code);
      if (e.code === 'KeyB') this.birdsEye = !this.birdsEye;
    });
    window.addEventListener('keyup', (e) => this.keys.delete(e.code));
    let dragging = null;
    element.addEventListener('mousedown', (e) => { dragging = { x: e.clientX, y: e.clientY }; });
    window.addEventListener('mouseup', () => { dragging = null; });
    window.addEventListener('mousemove', (e) => {
      if (!dragging) return;
      this.camera.yaw -= (e.clientX - dragging.x) * 0.2;
      this.camera.pitch = Math.max(-89, Math.min(89, this.camera.pitch - (e.clientY - dragging.y) * 0.2));
      dragging = { x: e.clientX, y: e.clientY };
    });
  }

  // Moves by what the keys held ask for over `seconds`.
  step(seconds) {
    const k = (...codes) => codes.some((c) => this.keys.has(c));
    const speed = (k('ShiftLeft', 'ShiftRight') ? 15 : 5) * seconds;
    const f = forward(this.camera.yaw, 0), r = [-f[2], 0, f[0]];
    const p = this.camera.position;
    const along = (k('KeyW', 'ArrowUp') ? 1 : 0) - (k('KeyS', 'ArrowDown') ? 1 : 0);
    const side = (k('KeyD', 'ArrowRight') ? 1 : 0) - (k('KeyA', 'ArrowLeft') ? 1 : 0);
    p[0] += (f[0] * along + r[0] * side) * speed;
    p[2] += (f[2] * along + r[2] * side) * speed;
    p[1] += ((k('KeyQ') ? 1 : 0) - (k('KeyE') ? 1 : 0)) * speed;
  }
}

// The view from above the walker: straight down from high enough to see the cells around it.
export function birdsEyeCamera(camera, height) {
  const [x, y, z] = camera.position;
  return { position: [x, y + height, z], yaw: camera.yaw, pitch: -89.9 };
}
