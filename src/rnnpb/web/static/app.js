// rnnpb dashboard: one WebSocket to the server's shared session; the 3-D robot (three.js),
// the pointer panel and the plots are drawn here from the server's step messages.
// Text from the server (model and pattern names come from files, errors echo clients) is only
// ever set as textContent, never parsed as HTML; the page's CSP allows no inline script.
import * as THREE from "/static/vendor/three.module.min.js";

const RED = "#d63a3a", BLUE = "#2f6fd6";
const HISTORY = 120;                      // steps kept for the plots (the server replays as many)
const PATTERN_NAMES = {
  "1": "horizontal swing, opposite phase", "2": "vertical swing, in phase",
  "3": "rotation, opposite phase", "4": "rotation, in phase",
};
const JOINT_COLORS = ["#7b3fb5", "#d98a00", "#1b9e77", "#555"];

const $ = (id) => document.getElementById(id);
// A movement's description (the paper's patterns, the demonstrator's new shapes); any other
// name (even "__proto__") has none.
const describe = (p) => {
  const more = (dash.state && dash.state.movement_descriptions) || {};
  if (Object.hasOwn(PATTERN_NAMES, p)) return PATTERN_NAMES[p];
  return Object.hasOwn(more, p) ? more[p] : "";
};
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
  rendered3d: 0, markers: null, run: null, refusedSends: 0, replayed: 0,
};

// ---------------------------------------------------------------- connection
let ws = null;
function connect() {
  const proto = location.protocol === "https:" ? "wss:" : "ws:";
  ws = new WebSocket(`${proto}//${location.host}/ws`);
  ws.onopen = () => { dash.connected = true; updateStatus(); };
  ws.onclose = () => {
    dash.connected = false;
    setControlsEnabled(false);
    updateStatus();
    setTimeout(connect, 1000);
  };
  ws.onmessage = (event) => {
    const message = JSON.parse(event.data);
    if (message.type === "state") onState(message);
    else if (message.type === "history") onHistory(message);
    else if (message.type === "step") onStep(message);
    else if (message.type === "frame") onFrame(message);
    else if (message.type === "error") showError(message.message);
  };
}
// A command sent while disconnected would be lost: say so instead (the controls are
// disabled then, this covers scripted sends and the moment the connection drops).
function send(message) {
  if (ws && ws.readyState === WebSocket.OPEN) {
    // A command's answer is a state (it worked: an old command's error goes) or an error.
    if (message.type !== "hands" && message.type !== "ping") dash.awaitingAnswer = true;
    ws.send(JSON.stringify(message));
    return true;
  }
  dash.refusedSends += 1;
  if (message.type !== "hands") showError("not connected to the server: not sent, try again "
    + "once reconnected");
  return false;
}
dash.send = send;

// Every control that sends a command; disabled while there is no connection.
function setControlsEnabled(enabled) {
  document.querySelectorAll("#model, #start, #stop, #reset, #dt, .tab, #camera, #perception, "
    + "#camera-open, #patterns button, #teach-mode, #rename-apply").forEach((node) => {
    node.disabled = !enabled;
  });
  if (!enabled) { $("teach-confirm").disabled = true; $("teach-undo").disabled = true; }
  document.body.classList.toggle("offline", !enabled);
}

// Transient errors (a command's answer) show for a while; the state's standing problems (a
// model that cannot be used, a failed step, a recording that stopped) stay until resolved.
let transientError = null;
function showError(text) {
  dash.awaitingAnswer = false;
  dash.errors.push(text);
  transientError = text;
  clearTimeout(showError.timer);
  showError.timer = setTimeout(() => { transientError = null; showProblems(); }, 8000);
  showProblems();
  if (/camera/i.test(text)) {
    const mode = dash.state ? dash.state.mode : "demonstrator";
    $("camera-message").textContent = `${text}. The robot is still driven by the ${mode}; `
      + "connect a camera or try another index.";
  }
}
function standingProblems(state) {
  if (!state) return [];
  return [...new Set([state.model_error, state.error, state.recording_error].filter(Boolean))];
}
function showProblems() {
  const problems = standingProblems(dash.state);
  if (transientError && !problems.includes(transientError)) problems.unshift(transientError);
  const box = $("error");
  box.replaceChildren(...problems.map((p) => el("div", {}, p)));
  box.hidden = problems.length === 0;
}

// ---------------------------------------------------------------- state
function onState(state) {
  const first = dash.state === null;
  const previousModel = dash.state && dash.state.model;
  dash.state = state;
  if (dash.awaitingAnswer) { dash.awaitingAnswer = false; transientError = null; }
  showModels(state);
  if (document.activeElement !== $("dt")) $("dt").value = state.dt;
  // Another tab (or a successful switch) changed the mode: show it. A failed switch to the
  // webcam leaves the webcam panel shown, with the reason.
  if (state.mode !== shownMode.server) { shownMode.server = state.mode; showMode(state.mode); }
  if (state.mode === "webcam") $("camera-message").textContent = "";
  if (state.perception && document.activeElement !== $("perception")) {
    $("perception").value = state.perception;
  }
  $("frame").hidden = state.mode !== "webcam";
  buildPatternButtons(state);
  const pbKey = JSON.stringify(state.pattern_pb);
  if (pbKey !== onState.pbKey) { onState.pbKey = pbKey; projection = null; }
  if (first || state.model !== previousModel) {
    projection = null;
    if (state.rest_hands && !dash.markers) {
      dash.markers = state.rest_hands.slice();
      drawPointerPanel();
    }
  }
  if (state.run !== dash.run) startRun(state.run);
  setControlsEnabled(true);
  const canStart = !state.running && !state.loading && !!state.model;
  $("start").disabled = !canStart;
  $("start").title = state.model ? "" : `no model loaded${state.model_error ? `: ${state.model_error}` : ""}`;
  $("stop").disabled = !state.running;
  showReadoutsState(state);
  showTeaching(state);
  showProblems();
  updateStatus();
  drawPlots();
  showSafety(dash.lastStep);
  showRoutine(dash.lastStep);
}

// The model list, and the one chosen: while a model loads, the one being loaded.
function showModels(state) {
  const select = $("model");
  const names = [...select.options].map((o) => o.value);
  if (JSON.stringify(names) !== JSON.stringify(state.models)) {
    select.replaceChildren();
    for (const name of state.models) select.add(new Option(name, name));
  }
  const shown = state.loading_model || state.model;
  if (shown) select.value = shown;
}

// A new run (Reset, a model change, a restarted server): the plots and readouts start over.
function startRun(run) {
  dash.run = run;
  dash.history = [];
  dash.lastStep = null;
  clearReadouts();
  robotView.clear();
}

function onHistory(message) {
  if (message.run !== dash.run) return;
  const known = new Set(dash.history.map((s) => s.step));
  const steps = message.steps.filter((s) => !known.has(s.step));
  dash.replayed = steps.length;
  dash.history = [...steps, ...dash.history].slice(-HISTORY);
  if (dash.history.length) {
    dash.lastStep = dash.history[dash.history.length - 1];
    showReadouts(dash.lastStep);
    robotView.push(dash.lastStep);
  }
  updateStatus();
  drawPlots();
  drawPointerPanel();
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
  if (!dash.connected) {
    el.textContent = "disconnected — reconnecting… (controls are off until then)";
    el.classList.add("offline");
    return;
  }
  if (!s) { el.textContent = "connected"; return; }
  if (s.loading) {
    el.textContent = `loading model ${s.loading_model || ""}… (compiling the network, a few `
      + "seconds)";
    el.classList.add("loading");
  } else if (s.running) {
    el.textContent = `running · model ${s.model} · driven by ${s.mode} · step `
      + `${dash.lastStep ? dash.lastStep.step : 0}`;
    el.classList.add("running");
  } else if (!s.model) {
    el.textContent = `no model loaded${s.model_error ? " (see the message above)" : ""}`;
    el.classList.add("problem");
  } else {
    el.textContent = `stopped · model ${s.model} · press Start`;
  }
}

// The demonstrator performs patterns 1-4 only: those are its buttons, each saying whether the
// model learned it. Learned patterns it cannot perform are listed, for the mouse or webcam.
function buildPatternButtons(state) {
  const box = $("patterns");
  const key = JSON.stringify([state.patterns, state.demonstrator_patterns,
    state.demonstrator_pattern, (state.teaching && state.teaching.taught_shapes) || {}]);
  if (box.dataset.key === key) return;
  box.dataset.key = key;
  box.replaceChildren();
  // A shape taught by showing is learned under its own name (new-1, or what the person called
  // it): the button says so.
  const shapes = (state.teaching && state.teaching.taught_shapes) || {};
  for (const p of [...state.demonstrator_patterns, "pause"]) {
    const taughtAs = Object.hasOwn(shapes, p) && shapes[p] !== p ? shapes[p] : "";
    const learned = state.patterns.includes(p) || taughtAs !== "";
    // The paper's patterns are numbered; the new shapes (figure-eight, ...) go by their name.
    const title = Object.hasOwn(PATTERN_NAMES, p) ? `Pattern ${p}` : `New shape: ${p}`;
    const button = p === "pause"
      ? el("button", {}, "❚❚ Pause", el("small", {}, "hands held still"))
      : el("button", {}, `${title}${learned ? "" : " (novel)"}`,
        el("small", {}, `${describe(p)}${taughtAs ? ` — learned by showing, as ${taughtAs}`
          : learned ? "" : " — not learned by this model"}`));
    button.dataset.pattern = p;
    button.classList.toggle("active", state.demonstrator_pattern === p);
    button.onclick = () => send({ type: "pattern", pattern: p });
    box.appendChild(button);
  }
  const taught = (state.teaching && state.teaching.taught) || [];
  const others = state.patterns.filter((p) => !state.demonstrator_patterns.includes(p)
    && !taught.includes(p));
  const shown = taught.length ? `Taught by showing (teaching panel): ${taught.join(", ")}. ` : "";
  $("patterns-note").textContent = shown + (others.length
    ? `This model also learned ${others.join(", ")}: the demonstrator cannot perform `
      + `${others.length > 1 ? "them" : "it"}; trace ${others.length > 1 ? "them" : "it"} with `
      + "the mouse or in front of the webcam."
    : "");
}

// ---------------------------------------------------------------- recognition
// What the robot says it sees: a learned pattern only when it is confident, else "not sure"
// or "new movement" (rnnpb.model.recognition).
dash.readout = (step) => readout(step);  // what the readout says of a step (tests)
function readout(step) {
  // Recognition holds a name until another pattern has been the most likely for a few steps
  // (so the name does not flicker); while it waits, the page names the one taking over.
  const taking = takingOver(step);
  if (taking) {
    const about = describe(taking);
    return `${taking}${about ? ` — ${about}` : ""} ` +
      `(${Math.round(100 * step.pattern_confidence[taking])} %, confirming; was ${step.recognised})`;
  }
  if (step.recognised && (step.novelty === "familiar" || step.novelty === "still")) {
    const still = step.novelty === "still" ? ", hands still" : "";
    const about = describe(step.recognised);
    return `${step.recognised}${about ? ` — ${about}` : ""} ` +
      `(${Math.round(100 * step.confidence)} %${still})`;
  }
  const words = { novel: "a new movement", unstructured: "not sure (no repeating pattern)",
    still: "hands still", "": "not sure yet" };
  return words[step.novelty] || "not sure";
}

// The learned pattern more likely than the name recognition still holds, and more likely
// than not, if any.
function takingOver(step) {
  const shares = step.pattern_confidence || {};
  if (!step.recognised || step.novelty !== "familiar") return null;
  let best = null;
  for (const [name, share] of Object.entries(shares)) {
    if (name !== step.recognised && share > Math.max(step.confidence, 0.5)
      && (!best || share > shares[best])) best = name;
  }
  return best;
}

function drawConfidenceBars(step) {
  const box = $("confidence-bars");
  if (!box) return;
  const shares = step.pattern_confidence || {};
  const names = Object.keys(shares);
  // Rebuilt whenever the names change (another model may have as many patterns).
  if (box.dataset.names !== JSON.stringify(names)) {
    box.dataset.names = JSON.stringify(names);
    box.replaceChildren(...names.map((name) => {
      const row = el("div", { className: "confidence-row" });
      row.appendChild(el("span", { className: "confidence-name" }, name));
      const bar = el("span", { className: "confidence-bar" });
      bar.appendChild(el("span", { className: "confidence-fill" }));
      row.appendChild(bar);
      row.appendChild(el("span", { className: "confidence-value" }, ""));
      return row;
    }));
  }
  names.forEach((name, i) => {
    const row = box.children[i];
    const share = shares[name];
    // A width set through the CSS object model, not a style attribute (the page's
    // Content-Security-Policy forbids inline styles).
    row.querySelector(".confidence-fill").style.width = `${Math.round(100 * share)}%`;
    row.classList.toggle("active", name === step.recognised);
    row.querySelector(".confidence-value").textContent = `${Math.round(100 * share)} %`;
  });
}

// ---------------------------------------------------------------- steps
function onStep(step) {
  dash.lastStep = step;
  dash.steps += 1;
  dash.history.push(step);
  if (dash.history.length > HISTORY) dash.history.shift();
  robotView.push(step);
  showReadouts(step);
  updateStatus();
  drawPlots();
  drawPointerPanel();
  showSafety(step);
  showRoutine(step);
  showTeachingStatus(step.teaching, step);
}

// ---------------------------------------------------------------- teaching
// The teaching panel: what the novelty detector says, "recording a new movement (cycle 2 of
// 4)", the consolidation's progress, the result and its rename, the kept episodes and the
// model versions, Confirm and Undo (docs/dashboard.md, "Teaching").
const NOVELTY_WORDS = { familiar: "a learned pattern", novel: "a new movement",
  unstructured: "no repeating pattern", still: "hands still" };
function showTeachingStatus(status, step) {
  const teaching = dash.state && dash.state.teaching;
  if (!status || !teaching) return;
  const job = status.consolidation;
  let phase = status.phase, badge, text = status.text || "", progress = null, note = "";
  if (job && job.state === "running") {
    phase = "consolidating";
    badge = "consolidating";
    text = "learning the kept movement in the background — the robot keeps moving";
    progress = job.total ? job.iteration / job.total : null;
    note = `${Math.round(job.seconds)} s${job.total ? ` · iteration ${job.iteration} of `
      + `${job.total}` : ""}`;
  } else if (phase === "recording") {
    badge = "recording";
    progress = Math.min(status.cycles, status.episode_cycles) / status.episode_cycles;
    note = `${Math.min(status.cycles, status.episode_cycles)} of ${status.episode_cycles} whole `
      + "cycles";
  } else if (phase === "kept") {
    badge = "kept";
    text = `new movement kept in the short-term memory${seenText(teaching)}`;
  } else if (phase === "off") {
    badge = "off";
    text = teaching.available ? "learning is off: nothing is kept"
      : (teaching.unavailable || status.text || "");
  } else {
    const novelty = step ? step.novelty : "";
    phase = novelty === "novel" ? "novel" : novelty === "familiar" ? "familiar" : "watching";
    badge = "watching";
    // Recording can start only when nothing waits (no kept movement before Confirm, no
    // learning, no swap of the model) and learning is on.
    const canRecord = teaching.available && teaching.mode !== "off" && !job
      && !teaching.waiting && !(dash.state && dash.state.loading);
    text = !step ? "start the robot and perform a movement"
      : NOVELTY_WORDS[novelty] ? `the robot sees ${NOVELTY_WORDS[novelty]}`
        + (novelty === "novel" && canRecord ? " — keep performing it: whole cycles are counted"
          : "")
        : "the robot is not sure yet what it sees";
    if (step) text += seenText(teaching);
  }
  const box = $("teach-phase");
  box.dataset.phase = phase;
  $("teach-badge").textContent = badge;
  $("teach-text").textContent = text;
  const bar = $("teach-progress");
  if (progress === null) bar.removeAttribute("value"); else bar.value = progress;
  bar.hidden = !(phase === "recording" || phase === "consolidating");
  $("teach-progress-text").textContent = note;
  dash.teachPhase = phase;
  const canConfirm = teaching.available && !job && (teaching.pending || 0) > 0;
  $("teach-confirm").disabled = !dash.connected || !canConfirm;
}

// How many performances the kept movements have: a new movement is learned from two (Confirm
// learns it from what was seen).
const TIMES = { 1: "once", 2: "twice" };
function seenText(teaching) {
  const seen = Object.entries(teaching.seen || {});
  if (!seen.length) return "";
  const needed = teaching.performances || 2;
  return " — " + seen.map(([pattern, n]) => `${pattern} seen ${TIMES[n] || `${n} times`}: `
    + (n < needed ? "show it again to learn it"
      + (teaching.mode === "confirm" ? " (or press Confirm to learn it from one)" : "")
      : teaching.mode === "confirm" ? "learn it now? press Confirm" : "learning it"))
    .join("; ");
}

function showTeaching(state) {
  const teaching = state.teaching;
  if (!teaching) return;
  if (document.activeElement !== $("teach-mode")) $("teach-mode").value = teaching.mode;
  const result = $("teach-result");
  result.textContent = teaching.result || "";
  result.hidden = !teaching.result;
  const failure = $("teach-failure");
  failure.textContent = teaching.failure ? `${teaching.failure} — the running model stays` : "";
  failure.hidden = !teaching.failure;
  $("teach-undo").disabled = !dash.connected || !teaching.can_undo;
  $("teach-undo").title = teaching.can_undo
    ? `go back to ${teaching.versions[teaching.versions.length - 2].name}`
    : "nothing to undo: the robot runs its first version";
  // Rename: the patterns teaching learned, and the kept movements not learned yet.
  const names = [...(teaching.taught || []), ...(teaching.episodes || [])
    .filter((e) => e.status === "kept").map((e) => e.pattern)];
  const unique = [...new Set(names)];
  const select = $("rename-pattern");
  if (select.dataset.names !== JSON.stringify(unique)) {
    select.dataset.names = JSON.stringify(unique);
    select.replaceChildren(...unique.map((n) => new Option(n, n)));
  }
  $("rename").hidden = unique.length === 0;
  const rows = (teaching.episodes || []).map((e) => el("tr", {},
    el("td", {}, `#${e.id}`), el("td", {}, e.pattern),
    el("td", { className: `status-${e.status}` }, e.status),
    el("td", {}, `${e.n_cycles} cycles, ${e.n_steps} steps`),
    el("td", {}, e.merged ? `another performance of #${e.merged}` : ""), el("td", {}, e.source),
    el("td", {}, e.when)));
  $("teach-episodes").replaceChildren(rows.length
    ? el("tr", {}, ...["", "pattern", "status", "movement", "merged", "from", "kept"].map((h) =>
      el("th", {}, h)))
    : el("tr", {}, el("td", {}, "nothing kept yet")), ...rows);
  $("teach-versions").replaceChildren(...(teaching.versions || []).map((v) => {
    const item = el("li", { className: v.running ? "running" : "" }, v.name,
      el("small", {}, ` — ${v.patterns.join(", ")}${v.running ? " (running)" : ""}`));
    return item;
  }));
  $("teach-folder").textContent = [teaching.folder,
    teaching.memory ? `Short-term memory: ${teaching.memory}.` : ""].filter(Boolean).join(". ");
  showTeachingStatus(teaching.status, dash.lastStep && dash.run === state.run
    ? dash.lastStep : null);
}

// The readouts under the robot: the last step's, marked as such while stopped.
function showReadouts(step) {
  $("step").textContent = step.step;
  $("nearest").textContent = readout(step);
  // Only a learned pattern is shown as one; "hands still", "new movement", "not sure" are not.
  $("nearest").classList.toggle("unsure", !(step.recognised
    && (step.novelty === "familiar" || step.novelty === "still")) || !!takingOver(step));
  $("nearest-distance").textContent =
    `(nearest learned PB ${step.nearest}, distance ${fmt(step.nearest_distance, 2)})`;
  drawConfidenceBars(step);
  $("pred-error").textContent = step.prediction_error === null ? "—"
    : step.prediction_error.toExponential(1);
  $("truth").textContent = step.mode === "demonstrator" ? step.truth
    : step.mode === "pointer" ? "you (mouse)" : "you (webcam)";
}
function clearReadouts() {
  for (const id of ["nearest", "pred-error", "truth"]) $(id).textContent = "—";
  $("step").textContent = "0";
  $("nearest-distance").textContent = "";
  $("readouts-note").textContent = "";
}
function showReadoutsState(state) {
  const box = document.querySelector(".recognised");
  const stale = !state.running && dash.lastStep !== null;
  box.classList.toggle("stale", stale);
  $("readouts-note").textContent = state.loading ? "loading another model…"
    : stale ? `stopped: these are the values of step ${dash.lastStep.step}` : "";
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
  const camera = new THREE.PerspectiveCamera(30, 1, 0.01, 20);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x8899aa, 2.2));
  const sun = new THREE.DirectionalLight(0xffffff, 1.6);
  sun.position.set(1, 2, 2);
  scene.add(sun);

  const shell = new THREE.MeshStandardMaterial({ color: 0xdfe3ea, roughness: 0.5 });
  const dark = new THREE.MeshStandardMaterial({ color: 0x3b4350, roughness: 0.6 });
  const joint = new THREE.MeshStandardMaterial({ color: 0x8792a5, roughness: 0.4 });
  const grid = new THREE.GridHelper(2.4, 24, 0xb6bdc8, 0xd3d8df);
  grid.position.z = 0.5;  // the floor between the robot and the person
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

  const limb = (radius, material = shell) => {
    const mesh = new THREE.Mesh(new THREE.CylinderGeometry(radius, radius, 1, 16), material);
    scene.add(mesh);
    return mesh;
  };
  const arms = [0, 1].map(() => ({
    shoulder: add(new THREE.SphereGeometry(0.028, 16, 12), joint),
    elbow: add(new THREE.SphereGeometry(0.02, 16, 12), joint),
    hand: add(new THREE.SphereGeometry(0.024, 16, 12), dark),
    upper: limb(0.022), fore: limb(0.019),
  }));

  // The person (rnnpb.demonstrator.UserBody: a kneeling adult facing the robot), drawn
  // translucent so the robot stays in view behind: torso, head, and each arm from the
  // shoulder to the hand the robot perceives (the elbow is placed for the look only).
  const skin = new THREE.MeshStandardMaterial({ color: 0xc9a88e, roughness: 0.7,
    transparent: true, opacity: 0.55 });
  const cloth = new THREE.MeshStandardMaterial({ color: 0x6d7f99, roughness: 0.8,
    transparent: true, opacity: 0.35 });
  const person = { parts: [], arms: [] };
  const userShoulders = () => (dash.state && dash.state.user_shoulders)
    || [[1, -0.19, 0.95], [1, 0.19, 0.95]];
  function buildPerson() {
    // Kneeling, as UserBody's shoulder height says: head, torso, thighs, shins on the floor.
    const [l, r] = userShoulders();
    const mid = [(l[0] + r[0]) / 2, (l[1] + r[1]) / 2, (l[2] + r[2]) / 2];
    const width = Math.abs(r[1] - l[1]), hips = mid[2] - 0.5;
    person.parts.push(add(new THREE.BoxGeometry(width + 0.04, 0.52, 0.16), cloth,
      [mid[0] + 0.03, mid[1], mid[2] - 0.24]));
    person.parts.push(add(new THREE.BoxGeometry(width - 0.04, hips - 0.1, 0.15), cloth,
      [mid[0] + 0.03, mid[1], 0.1 + (hips - 0.1) / 2]));                     // thighs
    person.parts.push(add(new THREE.BoxGeometry(width - 0.04, 0.1, 0.4), cloth,
      [mid[0] + 0.22, mid[1], 0.05]));                                       // shins
    person.parts.push(add(new THREE.CylinderGeometry(0.04, 0.045, 0.08, 14), skin,
      [mid[0] + 0.03, mid[1], mid[2] + 0.05]));
    person.parts.push(add(new THREE.SphereGeometry(0.09, 20, 14), skin,
      [mid[0] + 0.03, mid[1], mid[2] + 0.17]));
    for (let side = 0; side < 2; side++) {
      person.arms.push({ upper: limb(0.035, cloth), fore: limb(0.03, skin),
        shoulder: add(new THREE.SphereGeometry(0.045, 14, 10), cloth, [l, r][side]) });
    }
  }
  buildPerson();
  const userHands = [RED, BLUE].map((color) => add(new THREE.SphereGeometry(0.035, 20, 14),
    new THREE.MeshStandardMaterial({ color, roughness: 0.35 })));
  const UPPER = 0.3, FORE = 0.3;  // the person's arm (UserBody.arm_reach is about 0.62)
  function userElbow(s, h, side) {
    // Bend away from the body and down: the elbow of a relaxed arm reaching forward.
    const d = new THREE.Vector3().subVectors(h, s), len = Math.min(d.length(), UPPER + FORE - 1e-3);
    const along = d.clone().normalize();
    const out = new THREE.Vector3(side === 0 ? -0.6 : 0.6, -1, 0);
    out.addScaledVector(along, -out.dot(along)).normalize();
    const a = (UPPER * UPPER - FORE * FORE + len * len) / (2 * len);
    const bend = Math.sqrt(Math.max(UPPER * UPPER - a * a, 0));
    return s.clone().addScaledVector(along, a).addScaledVector(out, bend);
  }
  function placePersonArm(side, hand) {
    const arm = person.arms[side];
    arm.upper.visible = arm.fore.visible = !!hand;
    userHands[side].visible = !!hand;
    if (!hand) return;
    const s = v3(userShoulders()[side]), h = v3(hand), e = userElbow(s, h, side);
    placeLimb(arm.upper, s, e);
    placeLimb(arm.fore, e, h);
    userHands[side].position.copy(h);
  }

  const up = new THREE.Vector3(0, 1, 0);
  function placeLimb(mesh, a, b) {
    const d = new THREE.Vector3().subVectors(b, a);
    mesh.position.copy(a).addScaledVector(d, 0.5);
    mesh.scale.set(1, Math.max(d.length(), 1e-4), 1);
    mesh.quaternion.setFromUnitVectors(up, d.clone().normalize());
  }

  // Orbit: drag turns, wheel zooms (no controls library needed for this much). The first
  // view looks over the person's right shoulder at the robot, which faces it: the mirror.
  const VIEW = { azimuth: 0.95, elevation: 0.16, distance: 2.45 };
  let { azimuth, elevation, distance } = VIEW;
  const target = v3([0.45, 0, 0.62]);  // between the robot and the person
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
  renderer.domElement.addEventListener("dblclick", () => {
    ({ azimuth, elevation, distance } = VIEW);
    needsDraw = true;
  });
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
  function clear() { previous = current = null; needsDraw = true; }
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
      placePersonArm(side, user ? (before ? lerp(before, user, t) : user) : null);
    }
    placeCamera();
    renderer.render(scene, camera);
    dash.rendered3d += 1;
  }
  requestAnimationFrame(frame);
  return { push, clear };
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

// Round tick values: steps of 1, 2 or 5 times a power of ten, or of 15/30/45/90 for degrees,
// so that no tick reads like 112.5°.
function niceTicks(lo, hi, count, steps = null) {
  const raw = (hi - lo) / Math.max(count, 1);
  let step;
  if (steps) step = steps.find((s) => s >= raw) || steps[steps.length - 1];
  else {
    const p = 10 ** Math.floor(Math.log10(raw || 1));
    step = [1, 2, 5, 10].map((m) => m * p).find((s) => s >= raw);
  }
  const ticks = [];
  for (let v = Math.ceil(lo / step - 1e-9) * step; v <= hi + 1e-9; v += step) {
    ticks.push(Math.abs(v) < step * 1e-9 ? 0 : v);
  }
  return ticks;
}

// Where the performer changed: a switch of the demonstrator's pattern or of who drives, and
// the stretches in pause (the demonstrator's pause, or the PB held while nothing is seen).
function plotEvents(steps) {
  const switches = [], pauses = [];
  let start = null;
  steps.forEach((s, i) => {
    const prev = steps[i - 1];
    if (prev && prev.step === s.step - 1 && (prev.truth !== s.truth || prev.mode !== s.mode)
        && s.truth !== "pause" && prev.truth !== "pause") {
      switches.push({ step: s.step, label: s.mode === "demonstrator" ? s.truth : s.mode });
    }
    const paused = s.truth === "pause" || s.held;
    if (paused && start === null) start = s.step;
    if (!paused && start !== null) { pauses.push([start, s.step - 1]); start = null; }
  });
  if (start !== null) pauses.push([start, steps[steps.length - 1].step]);
  return { switches, pauses };
}

function timePlot(canvas, { title, ymin, ymax, yunit, ysteps, yticks = 4, series }) {
  const g = setupCanvas(canvas), w = canvas.width, h = canvas.height;
  const left = 44, right = 10, top = 16, bottom = 30;
  const pw = w - left - right, ph = h - top - bottom;
  g.fillStyle = "#1d2430";
  g.fillText(title, left, 11);
  const steps = dash.history;
  const last = steps.length ? steps[steps.length - 1].step : HISTORY - 1;
  const first = Math.max(0, last - HISTORY + 1);
  const x = (step) => left + (pw * (step - first)) / (HISTORY - 1);
  const y = (v) => top + ph - (ph * (v - ymin)) / (ymax - ymin);
  g.strokeStyle = "#e3e6eb";
  g.fillStyle = "#6b7483";
  g.textAlign = "right";
  for (const v of niceTicks(ymin, ymax, yticks, ysteps)) {
    g.beginPath(); g.moveTo(left, y(v)); g.lineTo(left + pw, y(v)); g.stroke();
    g.fillText(`${+v.toFixed(2)}${yunit || ""}`, left - 4, y(v) + 4);
  }
  // Step ticks along the bottom; the axis name sits under the value labels, left of the
  // plot, where no tick label can reach it (a 5-digit step included).
  g.textAlign = "center";
  for (const s of niceTicks(first, first + HISTORY - 1, 6)) {
    g.strokeStyle = "#c5cbd4";
    g.beginPath(); g.moveTo(x(s), top + ph); g.lineTo(x(s), top + ph + 4); g.stroke();
    g.fillText(String(s), Math.min(Math.max(x(s), left + 12), w - 16), top + ph + 15);
  }
  g.textAlign = "left";
  g.fillText("step", 2, top + ph + 15);
  const { switches, pauses } = plotEvents(steps);
  g.save();
  g.beginPath(); g.rect(left, top, pw, ph); g.clip();
  g.fillStyle = "rgba(120, 130, 150, 0.13)";
  for (const [a, b] of pauses) g.fillRect(x(a - 0.5), top, x(b + 0.5) - x(a - 0.5), ph);
  for (const s of series) {
    g.strokeStyle = s.color;
    g.lineWidth = s.width || 1.6;
    g.setLineDash(s.dash || []);
    g.beginPath();
    let started = false, previous = null;
    for (const step of steps) {
      const v = s.value(step);
      const gap = previous !== null && step.step !== previous + 1;
      previous = step.step;
      if (v === null || v === undefined || Number.isNaN(v) || gap) { started = false; }
      if (v === null || v === undefined || Number.isNaN(v)) continue;
      if (started) g.lineTo(x(step.step), y(v)); else { g.moveTo(x(step.step), y(v)); started = true; }
    }
    g.stroke();
  }
  g.setLineDash([3, 3]);
  g.strokeStyle = "#127a5a";
  g.lineWidth = 1.2;
  g.fillStyle = "#127a5a";
  for (const sw of switches) {
    const sx = x(sw.step - 0.5);
    g.beginPath(); g.moveTo(sx, top); g.lineTo(sx, top + ph); g.stroke();
    g.fillText(`→ ${sw.label}`, sx + 3, top + 10);
  }
  g.restore();
  g.setLineDash([]);
  g.textAlign = "start";
  dash.plotMarks = { switches: switches.length, pauses: pauses.length };
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

// Learned points closer than a marker's size are drawn apart, each tied by a line to its
// true place (a small dot), so that no two markers hide each other.
function spreadMarkers(points, size) {
  const placed = points.map((p) => ({ ...p, lx: p.x, ly: p.y }));
  for (let round = 0; round < 30; round++) {
    let moved = false;
    for (let i = 0; i < placed.length; i++) {
      for (let j = i + 1; j < placed.length; j++) {
        const a = placed[i], b = placed[j];
        let dx = b.lx - a.lx, dy = b.ly - a.ly;
        const d = Math.hypot(dx, dy);
        if (d >= size) continue;
        if (d < 1e-6) { dx = 1; dy = -1; }
        const push = (size - d) / 2 + 0.5, n = Math.hypot(dx, dy);
        a.lx -= (dx / n) * push; a.ly -= (dy / n) * push;
        b.lx += (dx / n) * push; b.ly += (dy / n) * push;
        moved = true;
      }
    }
    if (!moved) break;
  }
  return placed;
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
  g.textAlign = "right";
  g.fillText(`${P.labels[0]} →`, m + pw, h - 4);
  g.textAlign = "start";
  g.save(); g.translate(11, 12 + ph); g.rotate(-Math.PI / 2);
  g.fillText(`${P.labels[1]} →`, 0, 0); g.restore();
  if (P.fixed) { g.fillText("0", m - 10, 12 + ph + 10); g.fillText("1", m + pw - 4, 12 + ph + 12); }
  drawRisk(g, P, project, X, Y, [m, 12, pw, ph]);
  // The trail first, the learned markers over it: the markers are what the trail is read by.
  g.strokeStyle = "rgba(224, 123, 0, 0.75)";
  g.lineWidth = 1.5;
  g.beginPath();
  trail.forEach((p, i) => (i ? g.lineTo(X(p[0]), Y(p[1])) : g.moveTo(X(p[0]), Y(p[1]))));
  g.stroke();
  const nearest = dash.lastStep && dash.lastStep.nearest;
  const SIZE = 16;
  const markers = spreadMarkers(learned.map(([name, p]) => ({ name, x: X(p[0]), y: Y(p[1]) })),
    SIZE + 2);
  for (const mk of markers) {
    if (Math.hypot(mk.lx - mk.x, mk.ly - mk.y) > 1) {
      g.strokeStyle = "#6b7483"; g.lineWidth = 1;
      g.beginPath(); g.moveTo(mk.x, mk.y); g.lineTo(mk.lx, mk.ly); g.stroke();
      g.fillStyle = "#1d2430";
      g.beginPath(); g.arc(mk.x, mk.y, 2.5, 0, 2 * Math.PI); g.fill();
    }
  }
  g.font = "bold 11px system-ui, sans-serif";
  g.textAlign = "center";
  for (const mk of markers) {
    // A short name fits in its square; a longer one (a pattern taught and renamed) is written
    // beside it, whole.
    const short = mk.name.length <= 3;
    g.fillStyle = mk.name === nearest ? "#127a5a" : "#8a93a3";
    g.strokeStyle = "#fff"; g.lineWidth = 2;
    g.beginPath(); g.rect(mk.lx - SIZE / 2, mk.ly - SIZE / 2, SIZE, SIZE); g.fill(); g.stroke();
    if (short) {
      g.fillStyle = "#fff";
      g.fillText(mk.name, mk.lx, mk.ly + 4);
      mk.labelLeft = mk.lx - SIZE / 2; mk.labelRight = mk.lx + SIZE / 2;
    } else {
      // Beside the square on the side where it fits whole (right, else left, else inside).
      const width = g.measureText(mk.name).width;
      let at = mk.lx + SIZE / 2 + 3;
      if (at + width > w - 2) at = mk.lx - SIZE / 2 - 3 - width;
      at = Math.min(Math.max(at, 2), w - 2 - width);
      g.textAlign = "left";
      g.strokeStyle = "rgba(255, 255, 255, 0.85)"; g.lineWidth = 3;
      g.strokeText(mk.name, at, mk.ly + 4);
      g.fillStyle = mk.name === nearest ? "#127a5a" : "#4a5260";
      g.fillText(mk.name, at, mk.ly + 4);
      g.textAlign = "center";
      mk.labelLeft = at; mk.labelRight = at + width;
    }
  }
  g.textAlign = "start";
  g.font = "11px system-ui, sans-serif";
  dash.pbMarkers = markers.map((mk) => ({ name: mk.name, x: mk.lx, y: mk.ly,
    labelLeft: mk.labelLeft, labelRight: mk.labelRight, width: w }));
  if (trail.length) {
    // The newest PB: a ring around its point, so that on a learned marker (recognition)
    // the marker's label still shows through.
    const p = trail[trail.length - 1];
    g.strokeStyle = "#e07b00"; g.lineWidth = 2.5;
    g.beginPath(); g.arc(X(p[0]), Y(p[1]), 12, 0, 2 * Math.PI); g.stroke();
    g.fillStyle = "#e07b00";
    g.beginPath(); g.arc(X(p[0]), Y(p[1]), 2, 0, 2 * Math.PI); g.fill();
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
    if (step.regime) parts.push(`regime: ${step.regime}`);
    if (step.inhibited_count) parts.push(`inhibited: ${step.inhibited_count}`);
    if (step.inhibited) parts.push(`inhibited now (${step.inhibited})`);
  }
  line.textContent = `Safety — ${parts.join(" · ")}`;
}

// The routine level (docs/routines.md), when the server was given routine files: the routine
// recognised and the movement it expects next (a line under the readouts, made here so that
// the page's markup stays as it is; no line when the server has no routine file).
function showRoutine(step) {
  const routines = dash.state && dash.state.routines;
  let line = $("routine-status");
  if (!routines || (!routines.on && !routines.note)) { if (line) line.remove(); return; }
  if (!line) {
    line = el("div", { id: "routine-status" });
    $("readouts-note").before(line);
  }
  if (!routines.on) { line.textContent = `Routine — ${routines.note}`; return; }
  if (!step || step.routine === undefined) { line.textContent = `Routine — ${routines.note}`; return; }
  if (!step.routine) { line.textContent = "Routine: none recognised yet"; return; }
  const when = step.switch_due ? "now" : (step.steps_left === null ? "" : `in about ${Math.max(0, Math.round(step.steps_left))} steps`);
  line.textContent = `Routine: ${step.routine} · next movement: ${step.anticipated || "—"}${when ? ` (${when})` : ""}`;
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
  // Range: the angles shown, rounded out to 30 degrees; ticks at 15, 30, 45 or 90 degrees.
  const angles = dash.history.flatMap((s) => s.motor.map((v) => v * deg));
  const ymin = angles.length ? Math.floor(Math.min(...angles) / 30) * 30 - 30 : -90;
  const ymax = angles.length ? Math.ceil(Math.max(...angles) / 30) * 30 + 30 : 90;
  timePlot($("plot-joints"), { title: "degrees", ymin, ymax, yunit: "°",
    ysteps: [15, 30, 45, 90, 180], yticks: 6, series });
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
$("model").onchange = (e) => {
  // Shown as loading at once; the server's state then confirms (or names the failure).
  if (send({ type: "model", name: e.target.value })) {
    $("status").textContent = `loading model ${e.target.value}…`;
  } else if (dash.state) showModels(dash.state);
};
$("dt").onchange = (e) => {
  const dt = parseFloat(e.target.value);
  if (dt >= 0.02 && dt <= 5) send({ type: "dt", dt });
  else {
    // The field shows the step the session runs at, not a value it refused.
    if (dash.state) e.target.value = dash.state.dt;
    showError("dt must be 0.02–5 s");
  }
};
$("pb-projection").onchange = () => drawPlots();
$("teach-mode").onchange = (e) => send({ type: "teach_mode", mode: e.target.value });
$("teach-confirm").onclick = () => send({ type: "teach", action: "confirm" });
$("teach-undo").onclick = () => send({ type: "teach", action: "undo" });
$("rename-apply").onclick = () => {
  const name = $("rename-name").value.trim();
  const pattern = $("rename-pattern").value;
  if (!name || !pattern) { showError("rename: choose a pattern and type its new name"); return; }
  if (send({ type: "rename", pattern, name })) $("rename-name").value = "";
};
document.querySelectorAll(".tab").forEach((tab) => {
  tab.onclick = () => {
    showMode(tab.dataset.mode);
    if (tab.dataset.mode === "pointer") sendMarkers();
    if (tab.dataset.mode === "webcam") $("camera-message").textContent = "opening the camera…";
    send({ type: "mode", mode: tab.dataset.mode });
  };
});
$("perception").onchange = () => send({ type: "perception", perception: $("perception").value });
$("camera-open").onclick = () => {
  const index = parseInt($("camera").value, 10);
  $("camera-message").textContent = "opening the camera…";
  send({ type: "camera", index });
  send({ type: "mode", mode: "webcam" });
};
jointLegend();
drawPointerPanel();
setControlsEnabled(false);
drawPlots();
connect();
