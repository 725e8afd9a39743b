// The dice_env viewer: replays the recorded throws embedded in the page with three.js.
//
// The page (written by dice_env.viewer.write_html) holds its data as JSON in
// <script type="application/json" id="dice-env-throws">: the recordings (frame times,
// centres of mass, orientations as quaternions w, x, y, z, the outcome), and what Python
// prepared for drawing them (each die's triangles and face texture, each throw's walls,
// floor and extent). World axes are the simulator's: metres, z up.

import * as THREE from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";

const SPEEDS = [1, 1 / 2, 1 / 5, 1 / 10, 1 / 20];
const HOLD = 1.5; // real seconds the outcome stays up before the next throw plays
const FLOOR_COLOUR = 0xe9e4d8;
const FLOOR_SHADE = 0xd9d2c2;
const WALL_COLOUR = 0x7fa6c9;
const BACKGROUND = 0x2f3640;
const VIEW_DIRECTION = new THREE.Vector3(-0.45, -1.0, 0.8).normalize(); // camera from target
const LIGHT_DIRECTION = new THREE.Vector3(0.35, -0.45, 1.0).normalize(); // sun from target

const data = JSON.parse(document.getElementById("dice-env-throws").textContent);
const recordings = data.recordings;
const count = recordings.length;

// --- Page layout and controls -------------------------------------------------------------

document.head.insertAdjacentHTML("beforeend", `<style>
  html, body { margin: 0; height: 100%; overflow: hidden; background: #2f3640;
    font: 14px system-ui, sans-serif; color: #f5f5f5; }
  canvas { display: block; }
  .dice-panel { position: absolute; background: rgba(20, 24, 30, 0.78); border-radius: 6px;
    padding: 8px 12px; }
  #dice-title { top: 10px; left: 10px; font-weight: 600; }
  #dice-outcome { top: 10px; right: 10px; max-width: 40ch; line-height: 1.5; }
  #dice-controls { left: 10px; right: 10px; bottom: 10px; display: flex; gap: 10px;
    align-items: center; flex-wrap: wrap; }
  #dice-slider { flex: 1; min-width: 120px; }
  #dice-time { font-variant-numeric: tabular-nums; min-width: 14ch; }
  #dice-controls button, #dice-controls select { font: inherit; }
</style>`);

document.body.insertAdjacentHTML("beforeend", `
  <div id="dice-title" class="dice-panel"></div>
  <div id="dice-outcome" class="dice-panel" hidden></div>
  <div id="dice-controls" class="dice-panel">
    <button id="dice-play" title="play / pause (space)">Pause</button>
    <input id="dice-slider" type="range" min="0" step="any" value="0"
      aria-label="simulated time">
    <span id="dice-time"></span>
    <label>speed <select id="dice-speed">
      ${SPEEDS.map((s) => `<option value="${s}">${s === 1 ? "1" : `1/${1 / s}`}</option>`).join("")}
    </select></label>
    <label>throw <select id="dice-throw">
      ${recordings.map((_, k) => `<option value="${k}">${k + 1} of ${count}</option>`).join("")}
    </select></label>
    <label>layout <select id="dice-layout">
      <option value="sequence">one after another</option>
      <option value="side">side by side</option>
    </select></label>
  </div>`);

const ui = {
  title: document.getElementById("dice-title"),
  outcome: document.getElementById("dice-outcome"),
  play: document.getElementById("dice-play"),
  slider: document.getElementById("dice-slider"),
  time: document.getElementById("dice-time"),
  speed: document.getElementById("dice-speed"),
  throw: document.getElementById("dice-throw"),
  layout: document.getElementById("dice-layout"),
};
ui.layout.value = data.layout;

// --- Scene --------------------------------------------------------------------------------

const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
renderer.setSize(window.innerWidth, window.innerHeight);
renderer.shadowMap.enabled = true;
renderer.shadowMap.type = THREE.PCFShadowMap;
document.body.prepend(renderer.domElement);

const scene = new THREE.Scene();
scene.background = new THREE.Color(BACKGROUND);
const camera = new THREE.PerspectiveCamera(40, window.innerWidth / window.innerHeight, 1e-3, 100);
camera.up.set(0, 0, 1);
const controls = new OrbitControls(camera, renderer.domElement);

const sky = new THREE.HemisphereLight(0xffffff, 0x8a7f70, 1.6);
sky.position.set(0, 0, 1); // the sky is up (+z)
scene.add(sky);
const sun = new THREE.DirectionalLight(0xffffff, 1.8);
sun.castShadow = true;
sun.shadow.mapSize.set(2048, 2048);
sun.shadow.radius = 4; // soft edges (PCF)
scene.add(sun, sun.target);

const state = { t: 0, playing: true, current: 0, layout: data.layout, hold: 0 };
let dirty = true; // the picture needs drawing again

// The page is ready once the face textures are in: then it draws and starts playing.
const textures = new THREE.LoadingManager(start);
const loader = new THREE.TextureLoader(textures);

// One geometry and material per die shape, shared by every die of that shape.
const shapes = data.shapes.map((shape) => {
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute("position", new THREE.Float32BufferAttribute(shape.position, 3));
  geometry.setAttribute("normal", new THREE.Float32BufferAttribute(shape.normal, 3));
  geometry.setAttribute("uv", new THREE.Float32BufferAttribute(shape.uv, 2));
  const map = loader.load(shape.texture);
  map.flipY = false; // the atlas's texture coordinates have v down (glTF's convention)
  map.colorSpace = THREE.SRGBColorSpace;
  map.anisotropy = renderer.capabilities.getMaxAnisotropy();
  // Flat shaded: every corner of a face carries the face's normal.
  const material = new THREE.MeshStandardMaterial({ map, roughness: 0.55 });
  return { geometry, material };
});

// Two floor shades, alternating on the grid so that side by side throws' tiles stand apart.
const floorMaterials = [FLOOR_COLOUR, FLOOR_SHADE].map((color) => new THREE.MeshStandardMaterial({
  color, roughness: 0.95, side: THREE.DoubleSide,
}));
const wallMaterial = new THREE.MeshStandardMaterial({
  color: WALL_COLOUR, transparent: true, opacity: 0.22, side: THREE.DoubleSide,
  depthWrite: false,
});

/** A flat convex polygon (corners in order) as a triangle fan. */
function polygonGeometry(corners) {
  const points = [];
  for (let i = 1; i + 1 < corners.length; i++) points.push(corners[0], corners[i], corners[i + 1]);
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute("position", new THREE.Float32BufferAttribute(points.flat(), 3));
  geometry.computeVertexNormals();
  return geometry;
}

// Each throw is a group (floor, walls, dice) that the layout moves as a whole.
const throws = recordings.map((recording, k) => {
  const view = data.throws[k];
  const group = new THREE.Group();
  for (const wall of view.walls) group.add(new THREE.Mesh(polygonGeometry(wall), wallMaterial));
  const floor = new THREE.Mesh(new THREE.BufferGeometry(), floorMaterials[0]);
  floor.receiveShadow = true;
  group.add(floor);
  const dice = view.dice.map((index) => {
    const mesh = new THREE.Mesh(shapes[index].geometry, shapes[index].material);
    mesh.castShadow = true;
    mesh.receiveShadow = true;
    group.add(mesh);
    return mesh;
  });
  scene.add(group);
  const t = recording.t;
  return { recording, view, group, floor, dice, end: t[t.length - 1] };
});

// --- Layout and camera --------------------------------------------------------------------

/** Place the throws: all at their own place (sequence) or on a grid (side by side). */
function applyLayout(layout) {
  const radius = Math.max(...throws.map((th) => th.view.radius));
  const cell = 2.2 * radius; // grid spacing (m)
  const columns = Math.ceil(Math.sqrt(count));
  throws.forEach((th, k) => {
    const { point, u, w } = th.view.floor;
    const [cx, cy] = th.view.centre;
    const [column, row] = [k % columns, Math.floor(k / columns)];
    if (layout === "side") {
      th.group.position.set(column * cell - cx, -row * cell - cy, 0);
    } else {
      th.group.position.set(0, 0, 0);
    }
    th.floor.material = floorMaterials[layout === "side" ? (column + row) % 2 : 0];
    // The floor: a square in the floor plane about the throw, a grid tile when side by side.
    const half = layout === "side" ? cell / 2 : Math.max(2, 10 * radius);
    const corner = (a, b) => point.map((p, i) => p + a * half * u[i] + b * half * w[i]);
    th.floor.geometry.dispose();
    th.floor.geometry = polygonGeometry([corner(-1, -1), corner(1, -1), corner(1, 1), corner(-1, 1)]);
  });
  frame();
}

/** Aim the camera (and the sun's shadow) at every die's path, over all throws as laid out. */
function frame() {
  const box = new THREE.Box3();
  const p = new THREE.Vector3();
  for (const th of throws) {
    for (const frameAt of th.recording.position) {
      for (const centre of frameAt) box.expandByPoint(p.fromArray(centre).add(th.group.position));
    }
    box.expandByScalar(th.view.size);
  }
  const sphere = box.getBoundingSphere(new THREE.Sphere());
  const radius = Math.max(sphere.radius, 3 * Math.max(...throws.map((th) => th.view.size)));
  const halfAngle = THREE.MathUtils.degToRad(camera.fov / 2);
  const fit = Math.min(halfAngle, Math.atan(Math.tan(halfAngle) * camera.aspect));
  const distance = (1.1 * radius) / Math.sin(fit);
  controls.target.copy(sphere.center);
  camera.position.copy(sphere.center).addScaledVector(VIEW_DIRECTION, distance);
  camera.near = distance / 100;
  camera.far = distance * 100;
  camera.updateProjectionMatrix();
  controls.update();

  sun.target.position.copy(sphere.center);
  sun.position.copy(sphere.center).addScaledVector(LIGHT_DIRECTION, 4 * radius);
  const shadow = sun.shadow.camera;
  shadow.left = shadow.bottom = -1.5 * radius;
  shadow.right = shadow.top = 1.5 * radius;
  shadow.near = 0.5 * radius;
  shadow.far = 8 * radius;
  shadow.updateProjectionMatrix();
  dirty = true;
}

// --- Playback -----------------------------------------------------------------------------

const quaternionA = new THREE.Quaternion();
const quaternionB = new THREE.Quaternion();

/** Index i of the frame with t[i] <= time < t[i + 1] (clamped to the recording). */
function frameIndex(t, time) {
  let lo = 0;
  let hi = t.length - 1;
  while (hi - lo > 1) {
    const mid = (lo + hi) >> 1;
    if (t[mid] <= time) lo = mid; else hi = mid;
  }
  return lo;
}

/** Put die j of throw th where it is at time (linear position, slerp orientation). */
function pose(th, j, time, mesh) {
  const { t, position, quaternion } = th.recording;
  const i = frameIndex(t, time);
  const i1 = Math.min(i + 1, t.length - 1);
  const alpha = i1 > i ? THREE.MathUtils.clamp((time - t[i]) / (t[i1] - t[i]), 0, 1) : 0;
  const [a, b] = [position[i][j], position[i1][j]];
  mesh.position.set(a[0] + alpha * (b[0] - a[0]), a[1] + alpha * (b[1] - a[1]),
    a[2] + alpha * (b[2] - a[2]));
  const [qa, qb] = [quaternion[i][j], quaternion[i1][j]]; // (w, x, y, z)
  quaternionA.set(qa[1], qa[2], qa[3], qa[0]);
  quaternionB.set(qb[1], qb[2], qb[3], qb[0]);
  mesh.quaternion.slerpQuaternions(quaternionA, quaternionB, alpha);
}

/** The time the slider runs to: the current throw's end, or the longest when side by side. */
function endTime() {
  return state.layout === "side" ? Math.max(...throws.map((th) => th.end)) : throws[state.current].end;
}

/** Show the state: every die's pose, the slider, the time, the outcome panel. */
function update() {
  throws.forEach((th, k) => {
    th.group.visible = state.layout === "side" || k === state.current;
    th.dice.forEach((mesh, j) => pose(th, j, Math.min(state.t, th.end), mesh));
  });
  const end = endTime();
  ui.slider.max = end;
  ui.slider.value = state.t;
  ui.time.textContent = `t = ${state.t.toFixed(3)} s / ${end.toFixed(3)} s`;
  ui.play.textContent = state.playing ? "Pause" : "Play";
  ui.throw.value = state.current;
  const th = throws[state.current];
  ui.outcome.hidden = state.t < th.end;
  if (!ui.outcome.hidden) ui.outcome.innerHTML = outcomeHtml(th.recording);
  ui.title.textContent = heading(th.recording, !ui.outcome.hidden);
  dirty = true;
}

function escapeHtml(text) {
  return String(text).replace(/[&<>"]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;" })[c]);
}

/** The heading: the page's title and the throw's target where it has one; once the dice
 * stop, their faces, the total of several read dice and the target's verdict. */
function heading(recording, stopped) {
  const o = recording.outcome;
  const target = Array.isArray(o.target) ? o.target.join(", ") : o.target;
  if (!stopped) return o.target === undefined ? data.title : `${data.title} · target ${target}`;
  let faces = `faces ${o.faces.join(", ")}`;
  if (o.faces.length > 1 && o.read.every(Boolean)) {
    faces += ` (total ${o.faces.reduce((a, b) => a + b, 0)})`;
  }
  const verdict = o.target === undefined ? "" : ` · target ${target}: ${o.success ? "success" : "failure"}`;
  return `${data.title}: ${faces}${verdict}`;
}

/** The outcome panel's text: faces landed, settled / decided, why void, the title. */
function outcomeHtml(recording) {
  const o = recording.outcome;
  const faces = o.faces.map((f, j) => (o.read[j] ? `${f}` : `${f} (leaning)`)).join(", ");
  const yes = (flag) => (flag ? "yes" : "no");
  const lines = [
    recording.title ? `<b>${escapeHtml(recording.title)}</b>` : "",
    `faces: <b>${escapeHtml(faces)}</b>`,
    `settled: ${yes(o.settled)} · decided: ${yes(o.decided)} · at ${o.time.toFixed(3)} s`,
    o.void ? `void: <b>${escapeHtml(o.void)}</b>` : "the throw counts",
  ];
  return lines.filter(Boolean).join("<br>");
}

/** Jump to simulated time t (clamped to the slider's range). */
function seek(t) {
  state.t = THREE.MathUtils.clamp(t, 0, endTime());
  state.hold = 0;
  update();
}

function select(k) {
  state.current = k;
  if (state.layout === "sequence") state.t = 0;
  state.hold = 0;
  update();
}

/** Advance playback by dt real seconds; a sequence moves on to the next throw after HOLD. */
function advance(dt) {
  const end = endTime();
  if (state.t < end) {
    state.t = Math.min(end, state.t + dt * Number(ui.speed.value));
  } else if (state.layout === "sequence" && state.current + 1 < count) {
    state.hold += dt;
    if (state.hold >= HOLD) select(state.current + 1);
  } else {
    state.playing = false;
  }
  update();
}

ui.play.addEventListener("click", () => {
  if (!state.playing && state.t >= endTime()) {
    if (state.layout === "sequence" && state.current + 1 === count) state.current = 0;
    state.t = 0;
  }
  state.playing = !state.playing;
  state.hold = 0;
  update();
});
ui.slider.addEventListener("input", () => {
  state.playing = false;
  seek(Number(ui.slider.value));
});
ui.throw.addEventListener("change", () => select(Number(ui.throw.value)));
ui.layout.addEventListener("change", () => {
  state.layout = ui.layout.value;
  applyLayout(state.layout);
  seek(state.t);
});
window.addEventListener("keydown", (event) => {
  // Space plays / pauses, except where it already acts (a focused button or menu).
  if (event.code === "Space" && !["BUTTON", "SELECT"].includes(event.target.tagName)) {
    event.preventDefault();
    ui.play.click();
  }
});
window.addEventListener("resize", () => {
  camera.aspect = window.innerWidth / window.innerHeight;
  camera.updateProjectionMatrix();
  renderer.setSize(window.innerWidth, window.innerHeight);
  dirty = true;
});
controls.addEventListener("change", () => { dirty = true; });

function render() {
  renderer.render(scene, camera);
  dirty = false;
}

let last;
function loop(now) {
  const dt = Math.min(0.1, (now - last) / 1000); // a hidden tab's pause is not played through
  last = now;
  if (state.playing) advance(dt);
  if (dirty) render();
  requestAnimationFrame(loop);
}

/** Draw the first picture and start playing (once the face textures are in). */
function start() {
  render();
  window.diceViewer.ready = true;
  last = performance.now();
  requestAnimationFrame(loop);
}

applyLayout(state.layout);
update();

// --- Test hook ----------------------------------------------------------------------------

window.diceViewer = {
  ready: false,
  frames: recordings,
  /** Pause and show simulated time t; draws at once, so the canvas shows it on return. */
  setTime(t) {
    state.playing = false;
    seek(t);
    render();
  },
  /** [x, y] canvas pixels (CSS, from the top left) of die j of throw k's centre of mass. */
  project(k, j) {
    const th = throws[k];
    const mesh = new THREE.Object3D();
    pose(th, j, Math.min(state.t, th.end), mesh);
    const p = mesh.position.add(th.group.position).project(camera);
    const canvas = renderer.domElement;
    return [((p.x + 1) / 2) * canvas.clientWidth, ((1 - p.y) / 2) * canvas.clientHeight];
  },
  /** The camera's matrices (column-major, as three.js keeps them) and the canvas size. */
  camera() {
    return {
      projection: camera.projectionMatrix.toArray(),
      view: camera.matrixWorldInverse.toArray(),
      width: renderer.domElement.clientWidth,
      height: renderer.domElement.clientHeight,
    };
  },
};
