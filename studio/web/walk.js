// Walking through the model at eye height: the arrow keys (or W A S D) walk and turn, a drag
// looks around. The eye stays EYE_HEIGHT_M above the ground under it (gravity: it falls to the
// ground at g, climbs steps up to STEP_M), and a wall stops it BODY_RADIUS_M short: both found
// by casting rays into the model, as a person would meet it. Coordinates are the preview's
// (Y up, metres).

import * as THREE from './vendor/three/three.module.js';

export const EYE_HEIGHT_M = 1.6;
const STEP_M = 0.4;
const BODY_RADIUS_M = 0.3;
const WALK_M_S = 1.4;
const RUN_M_S = 4.0;
const TURN_DEG_S = 90;
const G_M_S2 = 9.81;
// A key tapped (pressed and let go within one frame) still moves this far.
const TAP_M = 0.1;

const DOWN = new THREE.Vector3(0, -1, 0);

export class Walker {
  constructor(viewer) {
    this.viewer = viewer;
    this.active = false;
    this.held = new Set();
    this.tapped = new Set();
    this.fallSpeed = 0;
    this.yaw = 0;
    this.pitch = 0;
    this.last = 0;
    this.ray = new THREE.Raycaster();
  }

  // The first surface along `direction` from `origin` within `far`, or null.
  hit(origin, direction, far) {
    this.ray.set(origin, direction);
    this.ray.far = far;
    return this.ray.intersectObject(this.viewer.model, true)[0] || null;
  }

  // The height of the ground under (x, z), searching down from `fromY`; null when none.
  ground(x, z, fromY) {
    const h = this.hit(new THREE.Vector3(x, fromY, z), DOWN, 1e5);
    return h ? h.point.y : null;
  }

  // Starts walking where the camera stands: on the ground under it. False when there is none.
  start() {
    const cam = this.viewer.camera;
    const top = this.viewer.bounds.max.y + 1;
    const under = this.ground(cam.position.x, cam.position.z, Math.min(cam.position.y, top));
    const floor = under ?? this.ground(cam.position.x, cam.position.z, top);
    if (floor === null) return false;
    cam.position.y = floor + EYE_HEIGHT_M;
    const forward = new THREE.Vector3();
    cam.getWorldDirection(forward);
    this.yaw = Math.atan2(-forward.x, -forward.z);
    this.pitch = 0;
    this.fallSpeed = 0;
    this.active = true;
    this.orient();
    this.last = performance.now();
    requestAnimationFrame((t) => this.frame(t));
    return true;
  }

  stop() {
    this.active = false;
    this.held.clear();
  }

  orient() {
    const cam = this.viewer.camera;
    cam.up.set(0, 1, 0);
    cam.rotation.order = 'YXZ';
    cam.rotation.set(this.pitch, this.yaw, 0);
    cam.updateMatrixWorld();
  }

  look(dx, dy) {
    this.yaw -= dx * 0.004;
    this.pitch = Math.max(-1.45, Math.min(1.45, this.pitch - dy * 0.004));
    this.orient();
    this.viewer.draw();
  }

  key(e, down) {
    const k = e.key.length === 1 ? e.key.toLowerCase() : e.key;
    const moves = ['ArrowUp', 'ArrowDown', 'ArrowLeft', 'ArrowRight', 'w', 'a', 's', 'd', 'q', 'e', 'Shift'];
    if (!moves.includes(k)) return false;
    if (down) { this.held.add(k); this.tapped.add(k); } else { this.held.delete(k); }
    return true;
  }

  // One step of `distance` along the horizontal unit vector `dir`, unless a wall is nearer
  // than the step and the body's radius, at the eye or at the height of a step.
  move(dir, distance) {
    const cam = this.viewer.camera;
    const floor = cam.position.y - EYE_HEIGHT_M;
    for (const height of [EYE_HEIGHT_M, STEP_M + 0.05]) {
      const from = new THREE.Vector3(cam.position.x, floor + height, cam.position.z);
      if (this.hit(from, dir, distance + BODY_RADIUS_M)) return false;
    }
    const next = cam.position.clone().addScaledVector(dir, distance);
    // The ground where the foot lands: a crack narrower than the body (a joint between slabs,
    // a seam of the model) does not stop a walker, an edge does.
    let ahead = null;
    for (const reach of [0, BODY_RADIUS_M / 2, -BODY_RADIUS_M / 2]) {
      ahead = this.ground(next.x + dir.x * reach, next.z + dir.z * reach, floor + STEP_M + 0.05);
      if (ahead !== null) break;
    }
    if (ahead === null) return false;
    cam.position.copy(next);
    if (ahead > floor) cam.position.y = ahead + EYE_HEIGHT_M;
    return true;
  }

  frame(time) {
    if (!this.active) return;
    const dt = Math.min((time - this.last) / 1000, 0.1);
    this.last = time;
    const on = (...keys) => keys.some((k) => this.held.has(k) || this.tapped.has(k));
    const turn = (on('ArrowLeft', 'q') ? 1 : 0) - (on('ArrowRight', 'e') ? 1 : 0);
    if (turn) { this.yaw += turn * (TURN_DEG_S * Math.PI / 180) * Math.max(dt, 1 / 30); this.orient(); }
    const forward = (on('ArrowUp', 'w') ? 1 : 0) - (on('ArrowDown', 's') ? 1 : 0);
    const side = (on('d') ? 1 : 0) - (on('a') ? 1 : 0);
    if (forward || side) {
      const f = new THREE.Vector3(-Math.sin(this.yaw), 0, -Math.cos(this.yaw));
      const r = new THREE.Vector3(-f.z, 0, f.x);
      const dir = f.multiplyScalar(forward).addScaledVector(r, side).normalize();
      const speed = this.held.has('Shift') ? RUN_M_S : WALK_M_S;
      this.move(dir, Math.max(speed * dt, TAP_M));
    }
    this.tapped.clear();
    this.fall(dt);
    this.viewer.draw();
    requestAnimationFrame((t) => this.frame(t));
  }

  // Gravity: down towards the ground under the eye at g, never through it.
  fall(dt) {
    const cam = this.viewer.camera;
    const floor = this.ground(cam.position.x, cam.position.z, cam.position.y - EYE_HEIGHT_M + STEP_M);
    if (floor === null) return;
    const above = cam.position.y - EYE_HEIGHT_M - floor;
    if (above <= 1e-6) { this.fallSpeed = 0; return; }
    this.fallSpeed += G_M_S2 * dt;
    cam.position.y -= Math.min(this.fallSpeed * dt, above);
  }
}
