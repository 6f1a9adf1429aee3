// The real-time view of a scene: its geometry as the coordinator converts it (glTF, re-centred,
// Y up), each material in the colour restauro computes from its spectrum, seen from the scene's
// camera, with orbit, pan and zoom.

import * as THREE from './vendor/three/three.module.js';
import { OrbitControls } from './vendor/three/addons/controls/OrbitControls.js';
import { GLTFLoader } from './vendor/three/addons/loaders/GLTFLoader.js';
import { Walker } from './walk.js';

export class Viewer {
  constructor(canvas) {
    this.canvas = canvas;
    // No multisampling: with software GL (no GPU) it costs more than the model does. A still
    // view is drawn at twice the resolution instead (supersampled), one in motion (orbiting,
    // walking) at the screen's, so that a model of a million triangles keeps moving.
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: false });
    this.stillRatio = Math.min(2 * window.devicePixelRatio, 2);
    this.movingRatio = Math.min(window.devicePixelRatio, 2);
    this.renderer.setPixelRatio(this.stillRatio);
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(0x9fb4c8);
    this.camera = new THREE.PerspectiveCamera(40, 16 / 9, 0.1, 10000);
    this.controls = new OrbitControls(this.camera, canvas);
    this.controls.addEventListener('change', () => this.draw());
    this.controls.addEventListener('start', () => this.moving(true));
    this.controls.addEventListener('end', () => this.moving(false));
    // A preview light: the sky from above, and the sun from where the scene puts it (or from
    // the south-west when the scene has none), casting shadows.
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x6b5a48, 1.6));
    this.sun = new THREE.DirectionalLight(0xffffff, 2.0);
    this.sun.position.set(-0.5, 1.0, 0.8);
    this.sun.castShadow = true;
    this.sun.shadow.mapSize.set(2048, 2048);
    // Offsets against shadow acne (a surface shadowing itself in bands that move with the
    // canvas's size): the normal offset is a few texels of the shadow map, which spans the model.
    this.sun.shadow.bias = -0.001;
    this.sun.shadow.normalBias = 0.05;
    this.scene.add(this.sun, this.sun.target);
    this.renderer.shadowMap.enabled = true;
    // The shadows change only when the sun or the model does: the shadow map is drawn then, not
    // at every frame (a model of a million triangles costs as much to draw into it as to see).
    this.renderer.shadowMap.autoUpdate = false;
    this.model = null;
    this.view = null;
    // The notes' pins, picked before the model.
    this.pins = new THREE.Group();
    this.scene.add(this.pins);
    // The luminaires: a bulb, a line to what each aims at, its photometric solid or its cone.
    this.lamps = new THREE.Group();
    this.scene.add(this.lamps);
    // The calculation grids: an outline each, and once computed their false-colour map.
    this.grids = new THREE.Group();
    this.scene.add(this.grids);
    this.onNote = () => {};
    new ResizeObserver(() => this.resize()).observe(canvas);
    this.onPick = () => {};
    // A click (not the end of a drag) picks the surface under the pointer.
    let down = null;
    canvas.addEventListener('pointerdown', (e) => { down = [e.clientX, e.clientY]; });
    // Walking, a drag looks around.
    this.walker = new Walker(this);
    canvas.addEventListener('pointermove', (e) => {
      if (this.walker.active && (e.buttons & 1)) this.walker.look(e.movementX, e.movementY);
    });
    // A double-click on a surface makes it the point the view orbits around (and turns to).
    canvas.addEventListener('dblclick', (e) => this.pivot(e));
    canvas.addEventListener('pointerup', (e) => {
      if (down && Math.hypot(e.clientX - down[0], e.clientY - down[1]) < 4) this.pick(e);
      down = null;
    });
  }

  // The object, part and material under the pointer event `e`, given to `onPick`.
  pick(e) {
    if (!this.model) return;
    const r = this.canvas.getBoundingClientRect();
    const ndc = new THREE.Vector2(((e.clientX - r.left) / r.width) * 2 - 1, -((e.clientY - r.top) / r.height) * 2 + 1);
    const ray = new THREE.Raycaster();
    ray.setFromCamera(ndc, this.camera);
    const pin = ray.intersectObject(this.pins, true)[0];
    if (pin) { this.onNote(pin.object.userData.note); return; }
    const hit = ray.intersectObject(this.model, true)[0];
    if (!hit) return;
    const extras = hit.object.geometry.userData || {};
    this.picked = hit.point.clone();
    // The surface's normal, turned to face the camera (the side that was clicked).
    const normal = hit.face ? hit.face.normal.clone().transformDirection(hit.object.matrixWorld) : null;
    if (normal && normal.dot(ray.ray.direction) > 0) normal.negate();
    this.hit = hit;
    this.onPick({ object: extras.object, part: extras.part, material: extras.material, point: hit.point.toArray(), normal: normal && normal.toArray() });
  }

  // The keyboard's orbit, pan and zoom, for a person who does not use a mouse: the arrows orbit
  // around the centre (5° a press), with Shift they pan (a twentieth of the view's height), and
  // + and − zoom (10 % nearer or farther). True when `e` was one of these keys.
  nudge(e) {
    if (!this.model || this.walker.active) return false;
    const c = this.controls;
    const step = (5 * Math.PI) / 180;
    const pan = this.canvas.clientHeight / 20;
    const arrows = { ArrowLeft: [1, 0], ArrowRight: [-1, 0], ArrowUp: [0, 1], ArrowDown: [0, -1] };
    if (arrows[e.key] && e.shiftKey) c.pan(arrows[e.key][0] * pan, arrows[e.key][1] * pan);
    else if (arrows[e.key]) { c.rotateLeft(arrows[e.key][0] * step); c.rotateUp(arrows[e.key][1] * step); }
    else if (e.key === '+' || e.key === '=') c.dollyIn(1 / 1.1);
    else if (e.key === '-' || e.key === '_') c.dollyOut(1 / 1.1);
    else return false;
    this.draw();
    return true;
  }

  // The surface under the pointer event `e` becomes the centre of orbiting.
  pivot(e) {
    if (!this.model || this.walker.active) return;
    const r = this.canvas.getBoundingClientRect();
    const ndc = new THREE.Vector2(((e.clientX - r.left) / r.width) * 2 - 1, -((e.clientY - r.top) / r.height) * 2 + 1);
    const ray = new THREE.Raycaster();
    ray.setFromCamera(ndc, this.camera);
    const hit = ray.intersectObject(this.model, true)[0];
    if (!hit) return;
    this.controls.target.copy(hit.point);
    this.controls.update();
    this.draw();
  }

  // Where the point `p` (a THREE.Vector3) is drawn, in the page's CSS pixels.
  onScreen(p) {
    const q = p.clone().project(this.camera);
    const r = this.canvas.getBoundingClientRect();
    return [r.left + ((q.x + 1) / 2) * r.width, r.top + ((1 - q.y) / 2) * r.height];
  }

  // Drawing a view in motion (true) or a still one (false): the resolution to draw at.
  moving(on) {
    const ratio = on ? this.movingRatio : this.stillRatio;
    if (this.coarse && this.coarse.children.length > 0 && this.model.visible === on) {
      this.model.visible = !on;
      this.coarse.visible = on;
      this.draw();
    }
    if (this.renderer.getPixelRatio() === ratio) return;
    this.renderer.setPixelRatio(ratio);
    this.resize();
  }

  resize() {
    const { clientWidth: w, clientHeight: h } = this.canvas;
    if (w === 0 || h === 0) return;
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.draw();
  }

  draw() {
    this.renderer.render(this.scene, this.camera);
    this.frames = (this.frames || 0) + 1;
    // When the first model was first drawn, in ms from the page's opening (the time a
    // restorer waits for the model; the browser tests report it). Drawing only queues the GPU's
    // work: reading one pixel back waits until the frame is really made.
    if (this.model && this.firstModelFrameMs === undefined) {
      const gl = this.renderer.getContext();
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4));
      this.firstModelFrameMs = performance.now();
      this.canvas.dataset.firstFrameMs = String(Math.round(this.firstModelFrameMs));
    }
  }

  // Opens the scene `view` (from /api/scenes/{id}); resolves when its model is drawn.
  async open(view, glbUrl) {
    const gltf = await new GLTFLoader().loadAsync(glbUrl);
    if (this.model) this.scene.remove(this.model, this.coarse);
    this.model = gltf.scene;
    // A big model comes with a coarser copy (extras.restauro_coarse) drawn instead of it while
    // the view moves; it is kept apart, so that clicks and the walker meet the model itself.
    this.coarse = new THREE.Group();
    this.coarse.visible = false;
    for (const node of [...this.model.children]) {
      if (node.userData.restauro_coarse) this.coarse.add(node);
    }
    this.scene.add(this.model, this.coarse);
    // A Lambert material is drawn as one (no highlight), so that its pixels scale with its
    // colour as restauro's matte surfaces do; Cook–Torrance keeps glTF's rough metal-free PBR.
    // Each part gets its own material: a hypothesis may put two parts of one material in
    // different states.
    const lambert = new Set(view.materials.filter((m) => m.model === 'lambert').map((m) => m.name));
    this.meshes((o) => {
      o.castShadow = true;
      o.receiveShadow = true;
      if (lambert.has(o.material.name)) {
        // A part's photo (map) or vertex colours stay with it: detail over its spectrum.
        const { name, color, side, map, vertexColors } = o.material;
        o.material = new THREE.MeshLambertMaterial({ name, color, side, map, vertexColors });
      } else {
        o.material = o.material.clone();
      }
    });
    // The sun's shadows are cast by the model itself (the shadow map is drawn while still).
    this.coarse.traverse((o) => { o.castShadow = false; });
    const box = new THREE.Box3().setFromObject(this.model);
    this.bounds = box;
    const size = box.getSize(new THREE.Vector3()).length();
    this.camera.near = Math.max(size / 10000, 0.01);
    this.camera.far = size * 20 + 1000;
    this.update(view);
    this.home();
    return gltf;
  }

  // Calls `f` with every mesh of the model and of its coarse copy.
  meshes(f) {
    for (const root of [this.model, this.coarse]) {
      root.traverse((o) => { if (o.isMesh) f(o); });
    }
  }

  // A new revision of the open scene (same geometry): its materials' colours and its sun.
  update(view) {
    this.view = view;
    this.colour();
    this.placeSun(view.sun);
    this.placePins(view.annotations);
    this.placeLamps(view.lights);
    this.draw();
  }

  // Each part in the colour of its material in the state `variant` gives it (a `VariantView`;
  // null: every part in its base state), under the light `look` picks (a state's colour under
  // the light chosen). A material without that state keeps its base, as in the render.
  colour(variant = this.variant, look = this.look || ((s) => s)) {
    this.variant = variant;
    this.look = look;
    const materials = new Map(this.view.materials.map((m) => [m.name, m]));
    this.meshes((o) => {
      const extras = o.geometry.userData || {};
      const m = materials.get(extras.material ?? o.material.name);
      if (!m) return;
      const state = variant ? variant.parts[`${extras.object}/${extras.part}`] : 'base';
      const s = m.states.find((x) => x.state === state);
      const colour = s ? look(s).colour_linear_srgb : m.colour_linear_srgb;
      // A part with a photo or vertex colours shows them relative to their mean, as a
      // snapshot does: the spectrum's colour over the mean, times the photo.
      const mean = extras.detail_mean;
      o.material.color.setRGB(...(mean ? colour.map((c, k) => c / Math.max(mean[k], 1e-4)) : colour));
    });
    this.draw();
  }

  // A pin for each note: a red ball a little larger than a stone's joint at this scale.
  placePins(annotations) {
    this.pins.clear();
    const radius = this.bounds.getSize(new THREE.Vector3()).length() / 300;
    const geometry = new THREE.SphereGeometry(radius, 16, 8);
    const material = new THREE.MeshBasicMaterial({ color: 0xd02020 });
    for (const a of annotations) {
      const pin = new THREE.Mesh(geometry, material);
      pin.position.set(...a.position);
      pin.userData.note = a.title;
      this.pins.add(pin);
    }
  }

  // Each luminaire (`LightView`s with a position): a yellow bulb, a yellow line to the point it
  // aims at, and in orange its photometric solid — the distance from the bulb in each direction
  // proportional to the intensity there, the peak 1/25 of the model's size — or a spot's cone.
  placeLamps(lights) {
    this.lamps.clear();
    const size = this.bounds.getSize(new THREE.Vector3()).length();
    const bulb = new THREE.SphereGeometry(size / 400, 12, 6);
    const yellow = new THREE.MeshBasicMaterial({ color: 0xffd000 });
    const orange = new THREE.LineBasicMaterial({ color: 0xff8800 });
    const line = (points, material) => new THREE.LineSegments(new THREE.BufferGeometry().setFromPoints(points), material);
    for (const l of lights) {
      if (l.corners) {
        // An area light: its emitting rectangle, drawn as light (unshaded), from both sides.
        const c = l.corners.map((q) => new THREE.Vector3(...q));
        const quad = new THREE.BufferGeometry().setFromPoints([c[0], c[1], c[2], c[0], c[2], c[3]]);
        this.lamps.add(new THREE.Mesh(quad, new THREE.MeshBasicMaterial({ color: 0xfff4c0, side: THREE.DoubleSide, polygonOffset: true, polygonOffsetFactor: -2, polygonOffsetUnits: -2 })));
        continue;
      }
      if (!l.position) continue;
      const p = new THREE.Vector3(...l.position);
      const b = new THREE.Mesh(bulb, yellow);
      b.position.copy(p);
      this.lamps.add(b);
      const aim = l.aim ? new THREE.Vector3(...l.aim) : null;
      if (aim) this.lamps.add(line([p, aim], new THREE.LineBasicMaterial({ color: 0xffd000 })));
      const segments = [];
      if (l.solid) {
        const [rows, cols, scale] = [l.solid.length / 36, 36, size / 25];
        const at = (g, c) => p.clone().addScaledVector(new THREE.Vector3(...l.solid[g * cols + (c % cols)]), scale);
        for (let g = 0; g < rows; g++) {
          for (let c = 0; c < cols; c++) {
            segments.push(at(g, c), at(g, c + 1));
            if (g + 1 < rows) segments.push(at(g, c), at(g + 1, c));
          }
        }
      } else if (l.light.kind === 'spot' && aim) {
        const axis = aim.clone().sub(p);
        const length = axis.length();
        axis.normalize();
        const side = new THREE.Vector3(0, 1, 0).cross(axis);
        if (side.lengthSq() < 1e-6) side.set(1, 0, 0);
        side.normalize();
        const edge = axis.clone().applyAxisAngle(side, THREE.MathUtils.degToRad(l.light.cone_deg));
        let last = null;
        for (let k = 0; k <= 24; k++) {
          const d = edge.clone().applyAxisAngle(axis, (2 * Math.PI * k) / 24);
          const end = p.clone().addScaledVector(d, length);
          if (k % 4 === 0) segments.push(p, end);
          if (last) segments.push(last, end);
          last = end;
        }
      }
      if (segments.length) this.lamps.add(line(segments, orange));
    }
  }

  // Each calculation grid (`GridView`s): a rectangle's outline in cyan, or a list's points; a
  // computed grid (`computed(name)`: {url, legendPx, colours}) drawn over it, a rectangle as
  // its map (the server's PNG without the legend under it: u to the right, v up), a list's
  // points in their colours (linear sRGB).
  placeGrids(grids, computed = () => null) {
    this.grids.clear();
    const cyan = new THREE.LineBasicMaterial({ color: 0x00c8ff });
    const size = this.bounds ? this.bounds.getSize(new THREE.Vector3()).length() : 10;
    for (const g of grids) {
      const result = computed(g.name);
      if (g.corners) {
        const c = g.corners.map((p) => new THREE.Vector3(...p));
        this.grids.add(new THREE.LineLoop(new THREE.BufferGeometry().setFromPoints(c), cyan));
        if (result && result.url) this.grids.add(this.gridMap(c, result));
      } else {
        const points = g.points.map((p) => new THREE.Vector3(...p));
        const geometry = new THREE.BufferGeometry().setFromPoints(points);
        const colours = result && result.colours ? result.colours : points.map(() => [0, 0.78, 1]);
        geometry.setAttribute('color', new THREE.Float32BufferAttribute(colours.flat(), 3));
        const material = new THREE.PointsMaterial({ size: size / 150, vertexColors: true });
        this.grids.add(new THREE.Points(geometry, material));
      }
    }
    this.draw();
  }

  // A quad over the corners `c` textured with the grid's map.
  gridMap(c, result) {
    const geometry = new THREE.BufferGeometry().setFromPoints([c[0], c[1], c[2], c[0], c[2], c[3]]);
    geometry.setAttribute('uv', new THREE.Float32BufferAttribute([0, 0, 1, 0, 1, 1, 0, 0, 1, 1, 0, 1], 2));
    const texture = new THREE.TextureLoader().load(result.url, (t) => {
      // The legend is the bottom rows of the picture: the quad shows the rows above it.
      const h = t.image.height;
      t.offset.set(0, result.legendPx / h);
      t.repeat.set(1, (h - result.legendPx) / h);
      t.needsUpdate = true;
      this.draw();
    });
    texture.colorSpace = THREE.SRGBColorSpace;
    const material = new THREE.MeshBasicMaterial({
      map: texture, side: THREE.DoubleSide, polygonOffset: true, polygonOffsetFactor: -2, polygonOffsetUnits: -2,
    });
    const mesh = new THREE.Mesh(geometry, material);
    mesh.userData.grid = true;
    return mesh;
  }

  // The preview's sun along the scene's sun direction, its shadow camera over the model.
  placeSun(sun) {
    const box = this.bounds;
    const centre = box.getCenter(new THREE.Vector3());
    const radius = box.getSize(new THREE.Vector3()).length() / 2 || 1;
    const d = sun ? new THREE.Vector3(...sun.direction) : new THREE.Vector3(-0.5, 1.0, 0.8).normalize();
    this.sun.intensity = sun && sun.elevation_deg <= 0 ? 0 : 2.0;
    this.sun.position.copy(centre).addScaledVector(d, radius * 2);
    this.sun.target.position.copy(centre);
    const c = this.sun.shadow.camera;
    [c.left, c.right, c.top, c.bottom, c.near, c.far] = [-radius, radius, radius, -radius, radius * 0.5, radius * 4];
    c.updateProjectionMatrix();
    this.sun.shadow.normalBias = (3 * 2 * radius) / this.sun.shadow.mapSize.x;
    this.renderer.shadowMap.needsUpdate = true;
  }

  // Walking on (true: false when there is no ground under the camera) or off; orbiting then
  // turns around the point 5 m ahead.
  walk(on) {
    if (on) {
      if (!this.model || !this.walker.start()) return false;
      this.controls.enabled = false;
      this.moving(true);
      return true;
    }
    if (!this.walker.active) return false;
    this.walker.stop();
    this.moving(false);
    this.camera.up.set(0, 1, 0);
    this.controls.target.copy(this.ahead(5));
    this.controls.enabled = true;
    this.controls.update();
    return false;
  }

  // The point `m` metres ahead of the camera.
  ahead(m) {
    const d = new THREE.Vector3();
    this.camera.getWorldDirection(d);
    return this.camera.position.clone().addScaledVector(d, m);
  }

  // The camera as it stands, for a snapshot (the preview's coordinates).
  pose() {
    return {
      position: this.camera.position.toArray(),
      target: (this.walker.active ? this.ahead(5) : this.controls.target).toArray(),
      up: this.camera.up.toArray(),
      vertical_fov_deg: this.camera.fov,
    };
  }

  // Back to the scene's own camera.
  home() {
    this.fly(this.view.camera);
  }

  // To the pose `c` ({position, target, up, vertical_fov_deg}, the preview's coordinates).
  fly(c) {
    this.walk(false);
    this.camera.fov = c.vertical_fov_deg;
    this.camera.up.set(...c.up);
    this.camera.position.set(...c.position);
    this.controls.target.set(...c.target);
    this.camera.updateProjectionMatrix();
    this.controls.update();
    this.draw();
  }
}
