// The 3D replay of `thorarena view`. The Rust side computed every body's world pose per
// step (forward kinematics of the trace) and the shapes of each body; this script builds
// one three.js mesh per collision shape, moves the bodies to the poses of the step the
// timeline points at, and plots the keypoint error with a cursor at that step; when the
// trace has the feet's contacts, it draws the ground's reaction at each foot's centre of
// pressure and plots the feet's slip speed and load under the error plot.

import * as THREE from "three";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";
import {
  Chart,
  LineController,
  LineElement,
  PointElement,
  LinearScale,
  Legend,
  Tooltip,
  Filler,
} from "chart.js";

Chart.register(LineController, LineElement, PointElement, LinearScale, Legend, Tooltip, Filler);
Chart.defaults.animation = false;
Chart.defaults.maintainAspectRatio = false;

const scene = JSON.parse(document.getElementById("view-data").textContent);
const steps = scene.time_s.length;
const $ = (id) => document.getElementById(id);

const COLORS = {
  robot: 0x7f8fa6,
  sole: 0xe69f00,
  ghost: 0x2fbf71,
  keypoint: 0x0072b2,
  refKeypoint: 0x2fbf71,
  force: [0xd55e00, 0xcc79a7], // left, right
  foot: [0x009e73, 0x56b4e9], // first, second foot
};
const FOOT_CSS = ["#009e73", "#56b4e9"];

// --- renderer, camera, lights, ground -----------------------------------------------
const viewport = $("viewport");
let renderer;
try {
  renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
} catch (err) {
  const box = document.createElement("div");
  box.className = "error";
  box.textContent = `This browser cannot draw the 3D scene (WebGL unavailable): ${err.message}`;
  viewport.appendChild(box);
  throw err;
}
renderer.setPixelRatio(window.devicePixelRatio || 1);
renderer.domElement.id = "scene";
viewport.appendChild(renderer.domElement);

const world = new THREE.Scene();
world.background = new THREE.Color(0xdfe5ec);
const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 100);
camera.up.set(0, 0, 1); // the simulator's world is z-up
const controls = new OrbitControls(camera, renderer.domElement);
controls.enableDamping = false;

world.add(new THREE.HemisphereLight(0xffffff, 0x8090a0, 2.2));
const sun = new THREE.DirectionalLight(0xffffff, 1.6);
sun.position.set(2, -3, 5);
world.add(sun);

// The ground: a plane with a 0.5 m grid drawn into a repeating canvas texture (a texture
// rather than GridHelper lines, whose segments reaching behind the camera vanish under
// software WebGL).
function gridTexture() {
  const size = 128;
  const canvas = document.createElement("canvas");
  canvas.width = size;
  canvas.height = size;
  const ctx = canvas.getContext("2d");
  ctx.fillStyle = "#c9d1db";
  ctx.fillRect(0, 0, size, size);
  ctx.strokeStyle = "#8793a3";
  ctx.lineWidth = 3;
  ctx.strokeRect(0, 0, size, size);
  const texture = new THREE.CanvasTexture(canvas);
  texture.wrapS = THREE.RepeatWrapping;
  texture.wrapT = THREE.RepeatWrapping;
  texture.repeat.set(80, 80); // 40 m / 0.5 m cells
  texture.anisotropy = renderer.capabilities.getMaxAnisotropy();
  texture.colorSpace = THREE.SRGBColorSpace;
  return texture;
}
const ground = new THREE.Mesh(
  new THREE.PlaneGeometry(40, 40),
  new THREE.MeshStandardMaterial({ map: gridTexture(), roughness: 1 }),
);
world.add(ground);

// --- bodies ----------------------------------------------------------------------------
function geometry(shape) {
  const [a, b, c] = shape.size;
  switch (shape.kind) {
    case "box":
      return new THREE.BoxGeometry(2 * a, 2 * b, 2 * c);
    case "sphere":
      return new THREE.SphereGeometry(a, 16, 12);
    case "capsule": // three.js builds capsules and cylinders along y; ours lie along z
      return new THREE.CapsuleGeometry(a, 2 * b, 6, 16).rotateX(Math.PI / 2);
    case "cylinder":
      return new THREE.CylinderGeometry(a, a, 2 * b, 20).rotateX(Math.PI / 2);
    default:
      throw new Error(`unknown shape kind ${shape.kind}`);
  }
}

const geometries = scene.bodies.map((body) => body.shapes.map(geometry));

function buildBodies(materialFor) {
  return scene.bodies.map((body, b) => {
    const group = new THREE.Group();
    group.name = body.name;
    body.shapes.forEach((shape, s) => {
      const mesh = new THREE.Mesh(geometries[b][s], materialFor(shape));
      mesh.position.fromArray(shape.pos);
      mesh.quaternion.fromArray(shape.quat_xyzw);
      group.add(mesh);
    });
    return group;
  });
}

const robotMaterial = new THREE.MeshStandardMaterial({ color: COLORS.robot, roughness: 0.6, metalness: 0.1 });
const soleMaterial = new THREE.MeshStandardMaterial({ color: COLORS.sole, roughness: 0.6 });
const robot = new THREE.Group();
const robotBodies = buildBodies((s) => (s.sole ? soleMaterial : robotMaterial));
robotBodies.forEach((g) => robot.add(g));
world.add(robot);

// The reference ghost: translucent, not writing depth, so the robot shows through it.
const ghostMaterial = new THREE.MeshStandardMaterial({
  color: COLORS.ghost,
  transparent: true,
  opacity: 0.28,
  depthWrite: false,
});
const ghostAnchor = new THREE.Group(); // carries the re-anchoring transform when asked
const ghost = new THREE.Group();
ghostAnchor.add(ghost);
const ghostBodies = scene.reference_poses ? buildBodies(() => ghostMaterial) : [];
ghostBodies.forEach((g) => ghost.add(g));
world.add(ghostAnchor);

// --- keypoints and forces --------------------------------------------------------------
const keypointGeometry = new THREE.SphereGeometry(0.018, 12, 8);
function markers(count, material) {
  const group = new THREE.Group();
  for (let k = 0; k < count; k++) group.add(new THREE.Mesh(keypointGeometry, material));
  world.add(group);
  return group;
}
const nKeypoints = scene.keypoints_w[0].length;
const robotMarkers = markers(nKeypoints, new THREE.MeshBasicMaterial({ color: COLORS.keypoint }));
const refMarkers = markers(
  nKeypoints,
  new THREE.MeshBasicMaterial({ color: COLORS.refKeypoint, wireframe: true }),
);

const arrows = COLORS.force.map((color) => {
  const arrow = new THREE.ArrowHelper(new THREE.Vector3(1, 0, 0), new THREE.Vector3(), 0.1, color);
  world.add(arrow);
  return arrow;
});

const feet = scene.feet;
const footArrows = (feet ? feet.names : []).map((_, k) => {
  const arrow = new THREE.ArrowHelper(new THREE.Vector3(0, 0, 1), new THREE.Vector3(), 0.1, COLORS.foot[k % 2]);
  world.add(arrow);
  return arrow;
});

// --- state -----------------------------------------------------------------------------
let current = 0;
const layers = {
  robot: $("show-robot"),
  reference: $("show-reference"),
  anchored: $("anchor-reference"),
  forces: $("show-forces"),
  feet: $("show-feet"),
  keypoints: $("show-keypoints"),
  follow: $("follow"),
};
if (!scene.reference_poses) {
  layers.anchored.disabled = true;
}
if (!feet) {
  layers.feet.disabled = true;
  layers.feet.checked = false;
  $("feet-plot").classList.add("hidden");
} else {
  $("layout").classList.add("with-feet");
}

function placeBodies(groups, flat) {
  groups.forEach((g, b) => {
    const o = 7 * b;
    g.position.set(flat[o], flat[o + 1], flat[o + 2]);
    g.quaternion.set(flat[o + 3], flat[o + 4], flat[o + 5], flat[o + 6]);
  });
}

const scratch = new THREE.Vector3();
function placeArrows(i) {
  const scale = Math.max(0, Number($("force-scale").value) || 0) / 1000; // m per N
  scene.hand_force_w[i].forEach((f, side) => {
    const arrow = arrows[side];
    scratch.fromArray(f);
    const n = scratch.length();
    arrow.visible = layers.forces.checked && n * scale > 1e-3;
    if (!arrow.visible) return;
    const length = n * scale;
    arrow.position.fromArray(scene.hand_points_w[i][side]);
    arrow.setDirection(scratch.divideScalar(n));
    arrow.setLength(length, Math.min(0.06, 0.35 * length), Math.min(0.035, 0.2 * length));
  });
}

// The ground's reaction on each foot, at its centre of pressure, at the hand arrows' scale
// divided by ten (a foot carries the robot's weight, ten times a hand's usual force).
function placeFootArrows(i) {
  const scale = Math.max(0, Number($("force-scale").value) || 0) / 10000; // m per N
  footArrows.forEach((arrow, k) => {
    const cop = feet.cop_w[i][k];
    scratch.fromArray(feet.reaction_w[i][k]);
    const n = scratch.length();
    arrow.visible = layers.feet.checked && cop !== null && n * scale > 1e-3;
    if (!arrow.visible) return;
    const length = n * scale;
    arrow.position.fromArray(cop);
    arrow.setDirection(scratch.divideScalar(n));
    arrow.setLength(length, Math.min(0.06, 0.35 * length), Math.min(0.035, 0.2 * length));
  });
}

function rootOf(i) {
  const p = scene.robot_poses[i];
  return new THREE.Vector3(p[0], p[1], p[2]);
}

function frameCamera() {
  const root = rootOf(current);
  controls.target.copy(root);
  camera.position.copy(root).add(new THREE.Vector3(1.6, -1.9, 0.5));
  controls.update();
}

function setStep(i) {
  const step = Math.max(0, Math.min(steps - 1, Math.round(i)));
  const previousRoot = rootOf(current);
  current = step;
  placeBodies(robotBodies, scene.robot_poses[step]);
  if (scene.reference_poses) {
    placeBodies(ghostBodies, scene.reference_poses[step]);
    const a = scene.anchor[step];
    if (layers.anchored.checked) {
      ghostAnchor.position.set(a[0], a[1], a[2]);
      ghostAnchor.quaternion.set(a[3], a[4], a[5], a[6]);
    } else {
      ghostAnchor.position.set(0, 0, 0);
      ghostAnchor.quaternion.identity();
    }
  }
  robotMarkers.children.forEach((m, k) => m.position.fromArray(scene.keypoints_w[step][k]));
  refMarkers.children.forEach((m, k) => m.position.fromArray(scene.reference_keypoints_w[step][k]));
  robot.visible = layers.robot.checked;
  ghostAnchor.visible = layers.reference.checked;
  const showMarkers = layers.keypoints.checked || !scene.reference_poses;
  robotMarkers.visible = showMarkers && layers.keypoints.checked;
  refMarkers.visible = showMarkers && layers.reference.checked;
  placeArrows(step);
  if (feet) placeFootArrows(step);
  if (layers.follow.checked) {
    // Keep the view relative to the robot: move camera and target by the root's motion.
    const delta = rootOf(step).sub(previousRoot);
    camera.position.add(delta);
    controls.target.add(delta);
    controls.update();
  }
  $("timeline").value = String(step);
  $("time-label").textContent = `${scene.time_s[step].toFixed(2)} s · ${scene.kp_err_mm[step].toFixed(1)} mm`;
  plot.update("none");
  if (footPlot) footPlot.update("none");
  requestRender();
}

// --- rendering -------------------------------------------------------------------------
let renderPending = false;
function render() {
  renderPending = false;
  const w = viewport.clientWidth;
  const h = viewport.clientHeight;
  if (w > 0 && h > 0) {
    const size = renderer.getSize(new THREE.Vector2());
    if (size.x !== w || size.y !== h) {
      renderer.setSize(w, h, false);
      camera.aspect = w / h;
      camera.updateProjectionMatrix();
    }
  }
  renderer.render(world, camera);
}
function requestRender() {
  if (!renderPending) {
    renderPending = true;
    requestAnimationFrame(render);
  }
}
controls.addEventListener("change", requestRender);
window.addEventListener("resize", requestRender);

// --- error plot with a cursor ----------------------------------------------------------
const cursor = {
  id: "thorarenaCursor",
  afterDatasetsDraw(chart) {
    const x = chart.scales.x.getPixelForValue(scene.time_s[current]);
    const { top, bottom } = chart.chartArea;
    const ctx = chart.ctx;
    ctx.save();
    ctx.strokeStyle = "#d55e00";
    ctx.lineWidth = 2;
    ctx.beginPath();
    ctx.moveTo(x, top);
    ctx.lineTo(x, bottom);
    ctx.stroke();
    ctx.restore();
  },
};
const totalForce = scene.hand_force_w.map((pair) => pair.reduce((s, f) => s + Math.hypot(f[0], f[1], f[2]), 0));
// A line chart over the episode's time with a left axis, a right "force" axis, the step
// cursor, and a click that moves the timeline.
function timeChart(canvasId, datasets, leftTitle, rightTitle) {
  return new Chart($(canvasId), {
    type: "line",
    data: { datasets },
    options: {
      parsing: false,
      normalized: true,
      elements: { point: { radius: 0 }, line: { borderWidth: 1.5 } },
      interaction: { mode: "nearest", axis: "x", intersect: false },
      scales: {
        x: { type: "linear", min: scene.time_s[0], max: scene.time_s[steps - 1], title: { display: true, text: "time (s)" } },
        y: { beginAtZero: true, title: { display: true, text: leftTitle } },
        force: { position: "right", beginAtZero: true, grid: { drawOnChartArea: false }, title: { display: true, text: rightTitle } },
      },
      plugins: { legend: { position: "top", align: "end" } },
      onClick: (event, _elements, chart) => {
        const t = chart.scales.x.getValueForPixel(event.x);
        setStep(nearestStep(t));
      },
    },
    plugins: [cursor],
  });
}
const series = (values) => scene.time_s.map((t, i) => ({ x: t, y: values(i) }));

const plot = timeChart(
  "kp-error-plot",
  [
    {
      label: "keypoint error (mm)",
      data: series((i) => scene.kp_err_mm[i]),
      borderColor: "#0072b2",
      backgroundColor: "rgba(0, 114, 178, 0.12)",
      fill: true,
      yAxisID: "y",
    },
    {
      label: "replayed hand force |F_L| + |F_R| (N)",
      data: series((i) => totalForce[i]),
      borderColor: "#cc79a7",
      borderDash: [4, 3],
      yAxisID: "force",
    },
  ],
  "keypoint error (mm)",
  "force (N)",
);

// The feet: slip speed of each (load-weighted over its sole points) and its normal force.
const footPlot = feet
  ? timeChart(
      "foot-slip-plot",
      feet.names.flatMap((name, k) => [
        {
          label: `${name}: slip speed (m/s)`,
          data: series((i) => feet.slip_speed_mps[i][k]),
          borderColor: FOOT_CSS[k % 2],
          yAxisID: "y",
        },
        {
          label: `${name}: normal force (N)`,
          data: series((i) => feet.normal_n[i][k]),
          borderColor: FOOT_CSS[k % 2],
          borderDash: [4, 3],
          borderWidth: 1,
          yAxisID: "force",
        },
      ]),
      "foot slip speed (m/s)",
      "normal force (N)",
    )
  : null;

function nearestStep(t) {
  let lo = 0;
  let hi = steps - 1;
  while (lo < hi) {
    const mid = (lo + hi) >> 1;
    if (scene.time_s[mid] < t) lo = mid + 1;
    else hi = mid;
  }
  if (lo > 0 && Math.abs(scene.time_s[lo - 1] - t) < Math.abs(scene.time_s[lo] - t)) lo -= 1;
  return lo;
}

// --- playback ----------------------------------------------------------------------------
let playing = false;
let simTime = 0; // s, advanced by wall time × speed while playing
let lastFrame = null;
function tick(now) {
  if (!playing) return;
  if (lastFrame !== null) simTime += ((now - lastFrame) / 1000) * Number($("speed").value);
  lastFrame = now;
  if (simTime >= scene.time_s[steps - 1]) {
    setStep(steps - 1);
    setPlaying(false);
    return;
  }
  const next = nearestStep(simTime);
  if (next !== current) setStep(next);
  requestAnimationFrame(tick);
}
function setPlaying(on) {
  playing = on;
  $("play").textContent = on ? "Pause" : "Play";
  if (on) {
    if (current >= steps - 1) setStep(0);
    simTime = scene.time_s[current];
    lastFrame = null;
    requestAnimationFrame(tick);
  }
}

$("play").addEventListener("click", () => setPlaying(!playing));
$("timeline").addEventListener("input", (e) => setStep(Number(e.target.value)));
for (const input of Object.values(layers)) input.addEventListener("change", () => setStep(current));
$("force-scale").addEventListener("input", () => setStep(current));
window.addEventListener("keydown", (e) => {
  if (e.target instanceof HTMLInputElement && e.target.type !== "range" && e.target.type !== "checkbox") return;
  if (e.key === " ") {
    e.preventDefault();
    setPlaying(!playing);
  } else if (e.key === "ArrowRight" || e.key === "ArrowLeft") {
    e.preventDefault();
    setStep(current + (e.key === "ArrowRight" ? 1 : -1));
  }
});

setStep(0);
frameCamera();
render();

// For tests and the console: the scene's size and a way to move in time.
window.thorarenaView = {
  ready: true,
  steps,
  bodies: scene.bodies.length,
  shapes: scene.bodies.reduce((n, b) => n + b.shapes.length, 0),
  ghost: Boolean(scene.reference_poses),
  feet: feet ? feet.names.length : 0,
  footPlot: footPlot
    ? footPlot.data.datasets.map((d) => ({ label: d.label, points: d.data.length, max: Math.max(...d.data.map((p) => p.y)) }))
    : null,
  get step() {
    return current;
  },
  setStep,
  render,
};
