// rnnpb dashboard: one WebSocket to the server's shared session; the 3-D robot (three.js),
// the pointer panel and the plots are drawn here from the server's step messages.
// Text from the server (model and pattern names come from files, errors echo clients) is only
// ever set as textContent, never parsed as HTML; the page's CSP allows no inline script.
import * as THREE from "/static/vendor/three.module.min.js";

const RED = "#d63a3a", BLUE = "#2f6fd6";
const HISTORY = 120;                      // steps kept for the plots
const PATTERN_NAMES = {
  "1": "horizontal swing, opposite phase", "2": "vertical swing, in phase",
  "3": "rotation, opposite phase", "4": "rotation, in phase",
};
const JOINT_COLORS = ["#7b3fb5", "#d98a00", "#1b9e77", "#555"];

const $ = (id) => document.getElementById(id);
// A learned pattern's description; any other name (even "__proto__") has none.
const describe = (p) => (Object.hasOwn(PATTERN_NAMES, p) ? PATTERN_NAMES[p] : "");
// An element with text children only: strings become text nodes, never markup.
function el(tag, props = {}, ...children) {
  const node = document.createElement(tag);
  Object.assign(node, props);
  node.append(...children.map((c) => (c instanceof Node ? c : String(c))));
  return node;
}
const fmt = (v, digits = 3) => (v === null || v === undefined || Number.isNaN(v)) ? "—"
  : Number(v).toFixed(digits);

// Shared with tests and the console: what the page knows.
const dash = window.rnnpbDashboard = {
  connected: false, state: null, lastStep: null, steps: 0, history: [], errors: [],
  rendered3d: 0, markers: null,
};

// ---------------------------------------------------------------- connection
let ws = null;
function connect() {
  const proto = location.protocol === "https:" ? "wss:" : "ws:";
  ws = new WebSocket(`${proto}//${location.host}/ws`);
  ws.onopen = () => { dash.connected = true; updateStatus(); };
  ws.onclose = () => {
    dash.connected = false; updateStatus();
    setTimeout(connect, 1000);
  };
  ws.onmessage = (event) => {
    const message = JSON.parse(event.data);
    if (message.type === "state") onState(message);
    else if (message.type === "step") onStep(message);
    else if (message.type === "frame") onFrame(message);
    else if (message.type === "error") showError(message.message);
  };
}
function send(message) {
  if (ws && ws.readyState === WebSocket.OPEN) ws.send(JSON.stringify(message));
}
dash.send = send;

function showError(text) {
  dash.errors.push(text);
  const box = $("error");
  box.textContent = text;
  box.hidden = false;
  clearTimeout(showError.timer);
  showError.timer = setTimeout(() => { box.hidden = true; }, 8000);
  if (/camera/i.test(text)) {
    const mode = dash.state ? dash.state.mode : "demonstrator";
    $("camera-message").textContent = `${text}. The robot is still driven by the ${mode}; `
      + "connect a camera or try another index.";
  }
}

// ---------------------------------------------------------------- state
function onState(state) {
  const first = dash.state === null;
  const previousModel = dash.state && dash.state.model;
  dash.state = state;
  const select = $("model");
  if (select.options.length !== state.models.length) {
    select.replaceChildren();
    for (const name of state.models) select.add(new Option(name, name));
  }
  if (state.model) select.value = state.model;
  if (document.activeElement !== $("dt")) $("dt").value = state.dt;
  // Another tab (or a successful switch) changed the mode: show it. A failed switch to the
  // webcam leaves the webcam panel shown, with the reason.
  if (state.mode !== shownMode.server) { shownMode.server = state.mode; showMode(state.mode); }
  if (state.mode === "webcam") $("camera-message").textContent = "";
  $("frame").hidden = state.mode !== "webcam";
  buildPatternButtons(state);
  if (first || state.model !== previousModel) {
    projection = null;
    if (state.rest_hands && !dash.markers) {
      dash.markers = state.rest_hands.slice();
      drawPointerPanel();
    }
  }
  if (state.steps === 0) { dash.history = []; dash.lastStep = null; }
  $("start").disabled = state.running || state.loading || !state.model;
  $("stop").disabled = !state.running;
  updateStatus();
  drawPlots();
  showSafety(dash.lastStep);
}

const shownMode = { server: null, view: null };
function showMode(mode) {
  shownMode.view = mode;
  document.querySelectorAll(".tab").forEach((tab) =>
    tab.classList.toggle("active", tab.dataset.mode === mode));
  document.querySelectorAll(".mode-body").forEach((body) =>
    body.classList.toggle("active", body.dataset.mode === mode));
}

function updateStatus() {
  const el = $("status"), s = dash.state;
  el.className = "status";
  if (!dash.connected) { el.textContent = "disconnected — reconnecting…"; return; }
  if (!s) { el.textContent = "connected"; return; }
  if (s.loading) {
    el.textContent = `loading model ${s.model || ""}… (compiling the network, a few seconds)`;
    el.classList.add("loading");
  } else if (s.running) {
    el.textContent = `running · driven by ${s.mode} · step ${dash.lastStep ? dash.lastStep.step : 0}`;
    el.classList.add("running");
  } else {
    el.textContent = s.model ? `stopped · model ${s.model} · press Start` : "no model";
  }
}

function buildPatternButtons(state) {
  const box = $("patterns");
  const key = JSON.stringify([state.patterns, state.novel_patterns, state.demonstrator_pattern]);
  if (box.dataset.key === key) return;
  box.dataset.key = key;
  box.replaceChildren();
  const all = [...state.patterns, ...state.novel_patterns].sort();
  for (const p of [...all, "pause"]) {
    const novel = state.novel_patterns.includes(p);
    const button = p === "pause"
      ? el("button", {}, "❚❚ Pause", el("small", {}, "hands held still"))
      : el("button", {}, `Pattern ${p}${novel ? " (novel)" : ""}`,
        el("small", {}, `${describe(p)}${novel ? " — not learned" : ""}`));
    button.dataset.pattern = p;
    button.classList.toggle("active", state.demonstrator_pattern === p);
    button.onclick = () => send({ type: "pattern", pattern: p });
    box.appendChild(button);
  }
}

// ---------------------------------------------------------------- steps
function onStep(step) {
  dash.lastStep = step;
  dash.steps += 1;
  dash.history.push(step);
  if (dash.history.length > HISTORY) dash.history.shift();
  robotView.push(step);
  $("step").textContent = step.step;
  $("nearest").textContent = `${step.nearest} — ${describe(step.nearest)}`;
  $("nearest-distance").textContent = `(PB distance ${fmt(step.nearest_distance, 2)})`;
  $("pred-error").textContent = step.prediction_error === null ? "—"
    : step.prediction_error.toExponential(1);
  $("truth").textContent = step.mode === "demonstrator" ? step.truth
    : step.mode === "pointer" ? "you (mouse)" : "you (webcam)";
  updateStatus();
  drawPlots();
  drawPointerPanel();
  showSafety(step);
}

function onFrame(message) {
  const img = $("frame");
  img.src = `data:image/jpeg;base64,${message.jpeg}`;
  img.hidden = false;
}

// ---------------------------------------------------------------- 3-D robot
// Robot frame: x forward (towards the person), y to the robot's left, z up (metres).
// three.js: X = y, Y = z, Z = x (a rotation), so the camera in front looks at the robot.
const v3 = (p) => new THREE.Vector3(p[1], p[2], p[0]);

const robotView = (() => {
  const container = $("view3d");
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 1.5));
  container.appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color("#e9edf2");
  const camera = new THREE.PerspectiveCamera(38, 1, 0.01, 20);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x8899aa, 2.2));
  const sun = new THREE.DirectionalLight(0xffffff, 1.6);
  sun.position.set(1, 2, 2);
  scene.add(sun);

  const shell = new THREE.MeshStandardMaterial({ color: 0xdfe3ea, roughness: 0.5 });
  const dark = new THREE.MeshStandardMaterial({ color: 0x3b4350, roughness: 0.6 });
  const joint = new THREE.MeshStandardMaterial({ color: 0x8792a5, roughness: 0.4 });
  const grid = new THREE.GridHelper(2.4, 24, 0xb6bdc8, 0xd3d8df);
  scene.add(grid);

  const add = (geometry, material, position) => {
    const mesh = new THREE.Mesh(geometry, material);
    if (position) mesh.position.copy(v3(position));
    scene.add(mesh);
    return mesh;
  };
  // Body from humanoid.xml (boxes: half sizes; three.js boxes take full sizes in X=y, Y=z, Z=x).
  add(new THREE.BoxGeometry(0.15, 0.18, 0.10), shell, [0, 0, 0.33]);            // chest
  add(new THREE.BoxGeometry(0.15, 0.06, 0.09), dark, [0, 0, 0.215]);            // pelvis
  for (const y of [0.045, -0.045]) {
    add(new THREE.CylinderGeometry(0.032, 0.032, 0.16, 16), shell, [0, y, 0.11]); // legs
    add(new THREE.BoxGeometry(0.07, 0.024, 0.12), dark, [0.02, y, 0.012]);      // feet
  }
  add(new THREE.CylinderGeometry(0.015, 0.015, 0.05, 12), dark, [-0.01, 0, 0.445]); // neck
  add(new THREE.SphereGeometry(0.05, 24, 16), shell, [-0.025, 0, 0.52]);        // head
  add(new THREE.BoxGeometry(0.07, 0.036, 0.012), dark, [0.016, 0, 0.52]);       // visor

  const limb = (radius) => {
    const mesh = new THREE.Mesh(new THREE.CylinderGeometry(radius, radius, 1, 16), shell);
    scene.add(mesh);
    return mesh;
  };
  const arms = [0, 1].map(() => ({
    shoulder: add(new THREE.SphereGeometry(0.028, 16, 12), joint),
    elbow: add(new THREE.SphereGeometry(0.02, 16, 12), joint),
    hand: add(new THREE.SphereGeometry(0.024, 16, 12), dark),
    upper: limb(0.022), fore: limb(0.019),
  }));
  const userHands = [RED, BLUE].map((color) => add(new THREE.SphereGeometry(0.035, 20, 14),
    new THREE.MeshStandardMaterial({ color, roughness: 0.35 })));
  userHands.forEach((h) => { h.visible = false; });

  const up = new THREE.Vector3(0, 1, 0);
  function placeLimb(mesh, a, b) {
    const d = new THREE.Vector3().subVectors(b, a);
    mesh.position.copy(a).addScaledVector(d, 0.5);
    mesh.scale.set(1, Math.max(d.length(), 1e-4), 1);
    mesh.quaternion.setFromUnitVectors(up, d.clone().normalize());
  }

  // Orbit: drag turns, wheel zooms (no controls library needed for this much).
  let azimuth = 0.85, elevation = 0.22, distance = 1.55;
  const target = new THREE.Vector3(0, 0.5, 0.36);  // between the robot and the hands
  function placeCamera() {
    camera.position.set(
      target.x + distance * Math.cos(elevation) * Math.sin(azimuth),
      target.y + distance * Math.sin(elevation),
      target.z + distance * Math.cos(elevation) * Math.cos(azimuth));
    camera.lookAt(target);
  }
  let dragging = null;
  renderer.domElement.addEventListener("pointerdown", (e) => {
    dragging = { x: e.clientX, y: e.clientY };
    renderer.domElement.setPointerCapture(e.pointerId);
  });
  renderer.domElement.addEventListener("pointermove", (e) => {
    if (!dragging) return;
    azimuth -= (e.clientX - dragging.x) * 0.008;
    elevation = Math.min(1.4, Math.max(-0.2, elevation + (e.clientY - dragging.y) * 0.006));
    dragging = { x: e.clientX, y: e.clientY };
    needsDraw = true;
  });
  renderer.domElement.addEventListener("pointerup", () => { dragging = null; });
  renderer.domElement.addEventListener("wheel", (e) => {
    e.preventDefault();
    distance = Math.min(5, Math.max(0.6, distance * Math.exp(e.deltaY * 0.001)));
    needsDraw = true;
  }, { passive: false });

  // The server sends one pose per step; the view eases from the previous pose to the newest
  // over one step, so the arms move smoothly (one step behind).
  let previous = null, current = null, received = 0;
  const restPose = () => {
    const shoulders = (dash.state && dash.state.robot.shoulders) || [[0, 0.095, 0.4], [0, -0.095, 0.4]];
    return { shoulders, elbows: shoulders.map((s) => [s[0], s[1], s[2] - 0.1]),
      hands: shoulders.map((s) => [s[0], s[1], s[2] - 0.21]), user: [null, null] };
  };
  function push(step) {
    const shoulders = dash.state.robot.shoulders;
    const pose = { shoulders, elbows: step.arms.elbows, hands: step.arms.hands,
      user: step.user_hands };
    previous = current || pose;
    current = pose;
    received = performance.now();
    needsDraw = true;
  }
  function lerp(a, b, t) { return a.map((v, i) => v + (b[i] - v) * t); }

  // Draw only while something moves (easing between poses, turning the view), at most
  // about 30 times a second: an idle page costs no GPU or CPU.
  let lastDraw = 0, needsDraw = true;
  function frame(now) {
    requestAnimationFrame(frame);
    const dtMs = (dash.state ? dash.state.dt : 0.4) * 1000;
    const easing = current && now - received < dtMs + 50;
    if (!(needsDraw || easing || dragging) || now - lastDraw < 30) return;
    lastDraw = now;
    needsDraw = false;
    draw();
  }
  function draw() {
    const width = container.clientWidth, height = container.clientHeight;
    const canvas = renderer.domElement;
    if (canvas.width !== Math.floor(width * renderer.getPixelRatio())
        || canvas.height !== Math.floor(height * renderer.getPixelRatio())) {
      renderer.setSize(width, height);
      camera.aspect = width / Math.max(height, 1);
      camera.updateProjectionMatrix();
    }
    const dt = (dash.state ? dash.state.dt : 0.4) * 1000;
    const t = current ? Math.min(1, (performance.now() - received) / dt) : 1;
    const a = previous || restPose(), b = current || restPose();
    for (let side = 0; side < 2; side++) {
      const s = v3(b.shoulders[side]);
      const e = v3(lerp(a.elbows[side], b.elbows[side], t));
      const h = v3(lerp(a.hands[side], b.hands[side], t));
      const arm = arms[side];
      arm.shoulder.position.copy(s);
      arm.elbow.position.copy(e);
      arm.hand.position.copy(h);
      placeLimb(arm.upper, s, e);
      placeLimb(arm.fore, e, h);
      const user = b.user && b.user[side];
      const before = a.user && a.user[side];
      userHands[side].visible = !!user;
      if (user) userHands[side].position.copy(v3(before ? lerp(before, user, t) : user));
    }
    placeCamera();
    renderer.render(scene, camera);
    dash.rendered3d += 1;
  }
  requestAnimationFrame(frame);
  return { push };
})();

// ---------------------------------------------------------------- pointer panel
// The panel is the robot's camera view: x = Y (0 left .. 1 right), y = 1 - Z.
const pointerCanvas = $("pointer");
const grabs = new Map();   // pointerId -> hand index (0 left/red, 1 right/blue)
let pendingSend = false;

function panelToHand(e) {
  const rect = pointerCanvas.getBoundingClientRect();
  const y = Math.min(1, Math.max(0, (e.clientX - rect.left) / rect.width));
  const z = Math.min(1, Math.max(0, 1 - (e.clientY - rect.top) / rect.height));
  return [y, z];
}
function sendMarkers() {
  if (pendingSend) return;
  pendingSend = true;
  // Coalesce drags to one message per animation frame.
  requestAnimationFrame(() => {
    pendingSend = false;
    if (dash.markers) send({ type: "hands", hands: dash.markers.map((v) => +v.toFixed(5)) });
  });
}
pointerCanvas.addEventListener("pointerdown", (e) => {
  if (!dash.markers) return;
  const [y, z] = panelToHand(e);
  const taken = new Set(grabs.values());
  let best = -1, bestDistance = Infinity;
  for (const hand of [0, 1]) {
    if (taken.has(hand)) continue;
    const d = Math.hypot(dash.markers[2 * hand] - y, (dash.markers[2 * hand + 1] - z) * 0.75);
    if (d < bestDistance) { best = hand; bestDistance = d; }
  }
  if (best < 0) return;
  grabs.set(e.pointerId, best);
  pointerCanvas.setPointerCapture(e.pointerId);
  dash.markers[2 * best] = y;
  dash.markers[2 * best + 1] = z;
  sendMarkers();
  drawPointerPanel();
});
pointerCanvas.addEventListener("pointermove", (e) => {
  if (!grabs.has(e.pointerId)) return;
  const hand = grabs.get(e.pointerId);
  const [y, z] = panelToHand(e);
  dash.markers[2 * hand] = y;
  dash.markers[2 * hand + 1] = z;
  sendMarkers();
  drawPointerPanel();
});
const release = (e) => grabs.delete(e.pointerId);
pointerCanvas.addEventListener("pointerup", release);
pointerCanvas.addEventListener("pointercancel", release);

function drawPointerPanel() {
  const c = pointerCanvas, g = c.getContext("2d"), w = c.width, h = c.height;
  g.clearRect(0, 0, w, h);
  g.strokeStyle = "#e6e9ee";
  g.lineWidth = 1;
  for (let i = 1; i < 8; i++) {
    g.beginPath(); g.moveTo((i * w) / 8, 0); g.lineTo((i * w) / 8, h); g.stroke();
    g.beginPath(); g.moveTo(0, (i * h) / 8); g.lineTo(w, (i * h) / 8); g.stroke();
  }
  g.fillStyle = "#8a93a3";
  g.font = "12px system-ui, sans-serif";
  g.fillText("the robot's camera view (you face the robot)", 8, 16);
  const px = (y, z) => [y * w, (1 - z) * h];
  // Trail of what the robot perceived.
  const history = dash.history.slice(-30);
  for (const [hand, color] of [[0, RED], [1, BLUE]]) {
    g.strokeStyle = color + "55";
    g.lineWidth = 2;
    g.beginPath();
    let started = false;
    for (const s of history) {
      const y = s.observed[2 * hand], z = s.observed[2 * hand + 1];
      if (y === null || z === null) { started = false; continue; }
      const [x, yy] = px(y, z);
      if (started) g.lineTo(x, yy); else { g.moveTo(x, yy); started = true; }
    }
    g.stroke();
    const last = dash.lastStep;
    if (last && last.predicted_next[2 * hand] !== null) {
      const [x, yy] = px(last.predicted_next[2 * hand], last.predicted_next[2 * hand + 1]);
      g.strokeStyle = color;
      g.setLineDash([4, 3]);
      g.beginPath(); g.arc(x, yy, 14, 0, 2 * Math.PI); g.stroke();
      g.setLineDash([]);
    }
  }
  if (!dash.markers) return;
  for (const [hand, color, label] of [[0, RED, "L"], [1, BLUE, "R"]]) {
    const [x, y] = px(dash.markers[2 * hand], dash.markers[2 * hand + 1]);
    g.fillStyle = color;
    g.beginPath(); g.arc(x, y, 12, 0, 2 * Math.PI); g.fill();
    g.fillStyle = "#fff";
    g.font = "bold 12px system-ui, sans-serif";
    g.textAlign = "center"; g.textBaseline = "middle";
    g.fillText(label, x, y + 0.5);
    g.textAlign = "start"; g.textBaseline = "alphabetic";
  }
}
dash.panelPoint = (hand) => {  // page coordinates of a marker, for scripted input
  const rect = pointerCanvas.getBoundingClientRect();
  return [rect.left + dash.markers[2 * hand] * rect.width,
    rect.top + (1 - dash.markers[2 * hand + 1]) * rect.height];
};
dash.panelRect = () => {
  const r = pointerCanvas.getBoundingClientRect();
  return { left: r.left, top: r.top, width: r.width, height: r.height };
};

// ---------------------------------------------------------------- plots
function setupCanvas(canvas) {
  const g = canvas.getContext("2d");
  g.clearRect(0, 0, canvas.width, canvas.height);
  g.font = "11px system-ui, sans-serif";
  return g;
}

function timePlot(canvas, { title, ymin, ymax, yunit, series }) {
  const g = setupCanvas(canvas), w = canvas.width, h = canvas.height;
  const left = 42, right = 8, top = 16, bottom = 18;
  const pw = w - left - right, ph = h - top - bottom;
  g.fillStyle = "#1d2430";
  g.fillText(title, left, 11);
  g.strokeStyle = "#e3e6eb";
  g.fillStyle = "#6b7483";
  for (let i = 0; i <= 4; i++) {
    const v = ymin + ((ymax - ymin) * i) / 4, y = top + ph - (ph * i) / 4;
    g.beginPath(); g.moveTo(left, y); g.lineTo(left + pw, y); g.stroke();
    g.fillText(`${+v.toFixed(2)}${yunit || ""}`, 2, y + 4);
  }
  const steps = dash.history;
  g.fillText(steps.length ? `steps ${steps[0].step}–${steps[steps.length - 1].step}` : "steps",
    left + pw - 80, h - 4);
  const x = (i) => left + (pw * i) / (HISTORY - 1);
  const y = (v) => top + ph - (ph * (v - ymin)) / (ymax - ymin);
  g.save();
  g.beginPath(); g.rect(left, top, pw, ph); g.clip();
  for (const s of series) {
    g.strokeStyle = s.color;
    g.lineWidth = s.width || 1.6;
    g.setLineDash(s.dash || []);
    g.beginPath();
    let started = false;
    steps.forEach((step, i) => {
      const v = s.value(step);
      if (v === null || v === undefined || Number.isNaN(v)) { started = false; return; }
      if (started) g.lineTo(x(i), y(v)); else { g.moveTo(x(i), y(v)); started = true; }
    });
    g.stroke();
  }
  g.restore();
  g.setLineDash([]);
}

let projection = null;
function pbProjection(mode) {
  const state = dash.state;
  const pbs = state ? Object.values(state.pattern_pb) : [];
  if (mode === "01") return { origin: [0, 0, 0, 0], axes: [[1, 0, 0, 0], [0, 1, 0, 0]],
    labels: ["PB0", "PB1"], fixed: true };
  if (mode === "23") return { origin: [0, 0, 0, 0], axes: [[0, 0, 1, 0], [0, 0, 0, 1]],
    labels: ["PB2", "PB3"], fixed: true };
  if (pbs.length < 2) return pbProjection("01");
  // The plane through the learned PBs: their mean and the two main directions of their spread
  // (power iteration with deflation; for three patterns the plane holds all three exactly).
  const n = pbs[0].length;
  const mean = Array.from({ length: n }, (_, j) => pbs.reduce((a, p) => a + p[j], 0) / pbs.length);
  const centred = pbs.map((p) => p.map((v, j) => v - mean[j]));
  const cov = Array.from({ length: n }, (_, i) => Array.from({ length: n }, (_, j) =>
    centred.reduce((a, p) => a + p[i] * p[j], 0)));
  const axes = [];
  for (let k = 0; k < 2; k++) {
    let v = Array.from({ length: n }, (_, i) => 1 + i * 0.37 + k);
    for (let it = 0; it < 200; it++) {
      let u = cov.map((row) => row.reduce((a, c, j) => a + c * v[j], 0));
      for (const a of axes) {
        const d = u.reduce((s, x, j) => s + x * a[j], 0);
        u = u.map((x, j) => x - d * a[j]);
      }
      const norm = Math.hypot(...u) || 1;
      v = u.map((x) => x / norm);
    }
    axes.push(v);
  }
  return { origin: mean, axes, labels: ["direction 1", "direction 2"], fixed: false };
}

function drawPB() {
  const canvas = $("plot-pb"), g = setupCanvas(canvas), w = canvas.width, h = canvas.height;
  const mode = $("pb-projection").value;
  if (!projection || projection.mode !== mode) projection = { mode, ...pbProjection(mode) };
  const P = projection;
  const project = (pb) => P.axes.map((a) => a.reduce((s, c, j) => s + c * (pb[j] - P.origin[j]), 0));
  const learned = Object.entries((dash.state && dash.state.pattern_pb) || {})
    .map(([name, pb]) => [name, project(pb)]);
  const trail = dash.history.filter((s) => s.pb).slice(-60).map((s) => project(s.pb));
  // Scale: fixed [0, 1] for raw PB axes; else fit the learned PBs and the trail, equal aspect.
  let lo = [0, 0], hi = [1, 1];
  if (!P.fixed) {
    const pts = [...learned.map((l) => l[1]), ...trail];
    lo = [Math.min(...pts.map((p) => p[0])), Math.min(...pts.map((p) => p[1]))];
    hi = [Math.max(...pts.map((p) => p[0])), Math.max(...pts.map((p) => p[1]))];
    const span = Math.max(hi[0] - lo[0], hi[1] - lo[1], 0.05) * 1.25;
    const c = [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2];
    lo = [c[0] - span / 2, c[1] - span / 2];
    hi = [c[0] + span / 2, c[1] + span / 2];
  }
  const m = 30, pw = w - m - 10, ph = h - m - 12;
  const X = (v) => m + (pw * (v - lo[0])) / (hi[0] - lo[0]);
  const Y = (v) => 12 + ph - (ph * (v - lo[1])) / (hi[1] - lo[1]);
  g.strokeStyle = "#d9dde4";
  g.strokeRect(m, 12, pw, ph);
  g.fillStyle = "#6b7483";
  g.fillText(P.labels[0] + " →", m + pw - 80, h - 4);
  g.save(); g.translate(11, 12 + ph); g.rotate(-Math.PI / 2);
  g.fillText(P.labels[1] + " →", 0, 0); g.restore();
  if (P.fixed) { g.fillText("0", m - 10, 12 + ph + 10); g.fillText("1", m + pw - 4, 12 + ph + 12); }
  drawRisk(g, P, project, X, Y, [m, 12, pw, ph]);
  const nearest = dash.lastStep && dash.lastStep.nearest;
  for (const [name, p] of learned) {
    const x = X(p[0]), y = Y(p[1]);
    g.fillStyle = name === nearest ? "#127a5a" : "#9aa3b2";
    g.fillRect(x - 7, y - 7, 14, 14);
    g.fillStyle = "#fff";
    g.font = "bold 11px system-ui, sans-serif";
    g.textAlign = "center"; g.fillText(name, x, y + 4); g.textAlign = "start";
    g.font = "11px system-ui, sans-serif";
  }
  g.strokeStyle = "#e07b00";
  g.lineWidth = 1.5;
  g.beginPath();
  trail.forEach((p, i) => (i ? g.lineTo(X(p[0]), Y(p[1])) : g.moveTo(X(p[0]), Y(p[1]))));
  g.stroke();
  if (trail.length) {
    const p = trail[trail.length - 1];
    g.fillStyle = "#e07b00";
    g.beginPath(); g.arc(X(p[0]), Y(p[1]), 5, 0, 2 * Math.PI); g.fill();
  }
}

// The learned unsafe region (the safety map's risk, docs/safety.md), shaded under the trail:
// the server sends the risk on a grid of each view's plane once, with the state message. The
// grid becomes a small image (one pixel a cell, opacity = risk) drawn through the affine map
// that the plot's own projection makes of the grid's plane, so any view is covered exactly.
let riskImage = null;
function drawRisk(g, P, project, X, Y, box) {
  const safety = dash.state && dash.state.safety;
  const view = safety && safety.risk && safety.risk[projection.mode];
  if (!view) return;
  const [ea0, ea1, eb0, eb1] = view.extent, n = view.grid;
  if (!riskImage || riskImage.view !== view) {
    const canvas = document.createElement("canvas");
    canvas.width = n; canvas.height = n;
    const c = canvas.getContext("2d"), image = c.createImageData(n, n);
    view.risk.forEach((row, i) => row.forEach((risk, j) => {
      const k = 4 * (i * n + j);
      image.data.set([214, 58, 58, Math.round(255 * 0.55 * risk)], k);
    }));
    c.putImageData(image, 0, 0);
    riskImage = { view, canvas };
  }
  // Grid corner (a, b) of the plane → pixel: origin + a·axes[0] + b·axes[1], projected.
  const pixel = (a, b) => {
    const p = project(view.origin.map((o, k) => o + a * view.axes[0][k] + b * view.axes[1][k]));
    return [X(p[0]), Y(p[1])];
  };
  const o = pixel(ea0, eb0), u = pixel(ea1, eb0), v = pixel(ea0, eb1);
  g.save();
  g.beginPath(); g.rect(...box); g.clip();
  g.transform((u[0] - o[0]) / n, (u[1] - o[1]) / n, (v[0] - o[0]) / n, (v[1] - o[1]) / n,
    o[0], o[1]);
  g.imageSmoothingEnabled = true;
  g.drawImage(riskImage.canvas, 0, 0);
  g.restore();
}

// What guards the robot, and how many commands the filter changed (a line under the PB plot,
// made here so that the page's markup stays as it is).
function showSafety(step) {
  let line = $("safety-status");
  if (!line) {
    line = el("p", { id: "safety-status", className: "legend" });
    $("plot-pb").after(line);
  }
  const safety = (dash.state && dash.state.safety) || {};
  const parts = [safety.filter ? "command filter on" : "command filter off",
    safety.map ? `PB guard: ${safety.guard} (shaded: learned risk)` : "no safety map"];
  if (step) {
    parts.push(`prevented commands: ${step.prevented}`);
    if (step.filtered) parts.push(`last step ${step.filtered}: ${step.unsafe}`);
  }
  line.textContent = `Safety — ${parts.join(" · ")}`;
}

function drawTimings() {
  const table = $("timings");
  const steps = dash.history.slice(-50).filter((s) => s.timings_ms);
  if (!steps.length) { table.replaceChildren(el("tr", {}, el("td", {}, "no steps yet"))); return; }
  const names = Object.keys(steps[steps.length - 1].timings_ms);
  const median = (xs) => { const s = [...xs].sort((a, b) => a - b); return s[Math.floor(s.length / 2)]; };
  const ms = (v) => fmt(v, 2);
  const rows = names.map((n) => {
    const values = steps.map((s) => s.timings_ms[n]);
    return el("tr", {}, el("td", {}, n), el("td", {}, ms(values[values.length - 1])),
      el("td", {}, ms(median(values))), el("td", {}, ms(Math.max(...values))));
  });
  const last = steps[steps.length - 1];
  const total = names.reduce((a, n) => a + last.timings_ms[n], 0);
  table.replaceChildren(
    el("tr", {}, ...["section", "last ms", "median ms", "max ms"].map((h) => el("th", {}, h))),
    ...rows,
    el("tr", {}, el("th", {}, "step budget"),
      el("td", { colSpan: 3 }, `${fmt(total, 1)} of ${fmt(last.dt * 1000, 0)} ms`
        + ` · missed deadlines ${last.missed_deadlines}`)));
}

function drawPlots() {
  const hand = (i, key) => (s) => s[key][i];
  for (const [id, offset, label] of [["plot-hy", 0, "horizontal position Y (0 left … 1 right)"],
    ["plot-hz", 1, "vertical position Z (0 bottom … 1 top)"]]) {
    timePlot($(id), { title: label, ymin: 0, ymax: 1, series: [
      { color: RED, value: hand(offset, "observed") },
      { color: RED, value: hand(offset, "predicted"), dash: [5, 4] },
      { color: BLUE, value: hand(2 + offset, "observed") },
      { color: BLUE, value: hand(2 + offset, "predicted"), dash: [5, 4] },
    ] });
  }
  const deg = 180 / Math.PI;
  const series = [];
  for (let j = 0; j < 8; j++) {
    series.push({ color: JOINT_COLORS[j % 4], dash: j < 4 ? [] : [5, 3],
      value: (s) => s.motor[j] * deg });
  }
  // Range: the angles shown, rounded out to 30 degrees.
  const angles = dash.history.flatMap((s) => s.motor.map((v) => v * deg));
  const ymin = angles.length ? Math.floor(Math.min(...angles) / 30) * 30 - 30 : -90;
  const ymax = angles.length ? Math.ceil(Math.max(...angles) / 30) * 30 + 30 : 90;
  timePlot($("plot-joints"), { title: "degrees", ymin, ymax, yunit: "°", series });
  drawPB();
  drawTimings();
}

function jointLegend() {
  const names = ["shoulder pitch", "shoulder roll", "shoulder yaw", "elbow pitch"];
  // Colours set through the style object: the CSP refuses style attributes in markup.
  $("joint-legend").replaceChildren(...names.flatMap((n, i) => {
    const swatch = el("span", { className: "line" });
    swatch.style.background = JOINT_COLORS[i];
    return [swatch, `${n} `];
  }), "— solid: left arm, dashed: right arm");
}

// ---------------------------------------------------------------- controls
$("start").onclick = () => send({ type: "control", action: "start" });
$("stop").onclick = () => send({ type: "control", action: "stop" });
$("reset").onclick = () => send({ type: "control", action: "reset" });
$("model").onchange = (e) => send({ type: "model", name: e.target.value });
$("dt").onchange = (e) => {
  const dt = parseFloat(e.target.value);
  if (dt >= 0.02 && dt <= 5) send({ type: "dt", dt }); else showError("dt must be 0.02–5 s");
};
$("pb-projection").onchange = () => drawPlots();
document.querySelectorAll(".tab").forEach((tab) => {
  tab.onclick = () => {
    showMode(tab.dataset.mode);
    if (tab.dataset.mode === "pointer") sendMarkers();
    if (tab.dataset.mode === "webcam") $("camera-message").textContent = "opening the camera…";
    send({ type: "mode", mode: tab.dataset.mode });
  };
});
$("camera-open").onclick = () => {
  const index = parseInt($("camera").value, 10);
  $("camera-message").textContent = "opening the camera…";
  send({ type: "camera", index });
  send({ type: "mode", mode: "webcam" });
};
jointLegend();
drawPointerPanel();
drawPlots();
connect();
