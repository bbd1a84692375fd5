// The mirror game (docs/dashboard.md). DOM text only through textContent; no inline code.
import { follow } from "./hands.js";

const $ = (id) => document.getElementById(id);
const canvas = $("view");
const ctx = canvas.getContext("2d");
const REST = [0.62, 0.55, 0.38, 0.55]; // lhy lhz rhy rhz: where your hands start
let hands = REST.slice();
let robotA = null;
let robotB = null;
let mode = "person";
const pointers = new Map(); // pointerId -> index of the hand it drags (0 left, 1 right)
let anchors = null; // both hands where the single dragging pointer took them
let ws = null;
let lastSent = 0;

function connect() {
  ws = new WebSocket(`${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/ws/game`);
  ws.addEventListener("message", (event) => receive(JSON.parse(event.data)));
  ws.addEventListener("close", () => { $("status").textContent = "disconnected"; setTimeout(connect, 2000); });
}

function send(message) {
  if (ws && ws.readyState === WebSocket.OPEN) ws.send(JSON.stringify(message));
}

function receive(message) {
  if (message.type === "game_state") {
    $("status").textContent = message.status + (message.model ? ` — ${message.model}` : "");
    // One game at a time: Start while none runs, Stop while one does.
    const playing = message.status === "running" || message.status === "starting";
    $("start").disabled = playing;
    $("stop").disabled = !playing;
    const select = $("model");
    if (select.options.length === 0) {
      for (const name of message.models) {
        const option = document.createElement("option");
        option.value = name;
        option.textContent = name;
        select.appendChild(option);
      }
    }
  } else if (message.type === "game_step") {
    show(message);
  } else if (message.type === "game_error" || message.type === "error") {
    $("message").textContent = message.message;
  }
}

function show(step) {
  robotA = step.a;
  robotB = mode === "robots" ? step.b : null;
  $("meter").value = step.synchrony;
  const coherent = $("coherent");
  coherent.textContent = step.coherent ? `together on movement ${step.pattern}` : "not together";
  coherent.classList.toggle("on", step.coherent);
  $("hint").textContent = step.hint ? `try: ${step.hint}` : "";
  $("found").textContent = step.found.length
    ? `${step.found.length} of ${step.learned}` : `none yet (of ${step.learned})`;
  const list = $("found-list");
  if (list.children.length !== step.found_at.length) {
    list.replaceChildren(...step.found_at.map((f) => {
      const item = document.createElement("li");
      item.textContent = `movement ${f.pattern} at ${f.time_s.toFixed(1)} s`
        + (f.led_by ? `, led by ${f.led_by}` : "");
      return item;
    }));
  }
  $("leader").textContent = step.last_leader || "–";
  $("time").textContent = `${step.time_s.toFixed(1)} s (step ${step.step})`;
  draw();
  // Scripted players (benchmarks/game_players.py) move in step with the game.
  window.dispatchEvent(new CustomEvent("game-step", { detail: step }));
}

// The robot's camera sees your left hand on its right; the mirror view shows it on the left.
const mirrored = () => $("mirror-view").checked;
function toCanvas(y, z) {
  return [(mirrored() ? 1 - y : y) * canvas.width, (1 - z) * canvas.height];
}
function fromCanvas(x, y) {
  const across = Math.min(1, Math.max(0, x / canvas.width));
  return [mirrored() ? 1 - across : across, Math.min(1, Math.max(0, 1 - y / canvas.height))];
}

function dot(values, index, color, label, ring = false) {
  if (!values || values[2 * index] === null || values[2 * index + 1] === null) return;
  const [x, y] = toCanvas(values[2 * index], values[2 * index + 1]);
  ctx.beginPath();
  ctx.arc(x, y, ring ? 16 : 11, 0, 2 * Math.PI);
  // The second agent is a ring around where its hand is: on top of the first, both show.
  if (ring) {
    ctx.lineWidth = 4;
    ctx.strokeStyle = color;
    ctx.stroke();
    ctx.fillStyle = color;
    ctx.font = "11px sans-serif";
    ctx.textAlign = "center";
    ctx.textBaseline = "middle";
    ctx.fillText(label, x + 24, y);
    return;
  }
  ctx.fillStyle = color;
  ctx.fill();
  ctx.fillStyle = "#fff";
  ctx.font = "11px sans-serif";
  ctx.textAlign = "center";
  ctx.textBaseline = "middle";
  ctx.fillText(label, x, y);
}

function draw() {
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  ctx.fillStyle = "#888";
  ctx.font = "12px sans-serif";
  ctx.textAlign = "left";
  ctx.fillText(mode === "robots" ? "robot A (orange), robot B (green)"
    : `the robot (orange) and you (blue), ${mirrored() ? "as in a mirror" : "as the robot's camera sees you"}`, 8, 16);
  for (const i of [0, 1]) dot(robotA, i, "#e8772e", i ? "R" : "L");
  if (mode === "robots") for (const i of [0, 1]) dot(robotB, i, "#2e9e55", i ? "R" : "L", true);
  else for (const i of [0, 1]) dot(hands, i, "#2f6fdf", i ? "R" : "L", true);
}

// The free hand whose marker is nearest to where the pointer pressed (the one aimed at).
function nearest(px, py) {
  const taken = new Set(pointers.values());
  let best = null;
  let bestDistance = Infinity;
  for (const i of [0, 1]) {
    if (taken.has(i)) continue;
    const [x, y] = toCanvas(hands[2 * i], hands[2 * i + 1]);
    const d = Math.hypot(x - px, y - py);
    if (d < bestDistance) { best = i; bestDistance = d; }
  }
  return best;
}

// One pointer: the other hand as "Other hand" says; two fingers each drag their own.
function moveHand(index, y, z) {
  hands = follow(hands, anchors, index, y, z, pointers.size === 1 ? $("coupling").value : "still");
}

function position(event) {
  const rect = canvas.getBoundingClientRect();
  return [(event.clientX - rect.left) * canvas.width / rect.width,
    (event.clientY - rect.top) * canvas.height / rect.height];
}

function sendHands() {
  if (mode !== "person") return;
  lastSent = performance.now();
  send({ type: "game_hands", hands: hands.map((v) => +v.toFixed(5)) });
}

canvas.addEventListener("pointerdown", (event) => {
  const [x, y] = position(event);
  const hand = nearest(x, y);
  if (hand === null) return;
  pointers.set(event.pointerId, hand);
  anchors = hands.slice();
  // A pointer the browser no longer tracks (it ended meanwhile) cannot be captured.
  try { canvas.setPointerCapture(event.pointerId); } catch { /* moves still reach the canvas */ }
});
canvas.addEventListener("pointermove", (event) => {
  if (!pointers.has(event.pointerId)) return;
  const [x, y] = position(event);
  moveHand(pointers.get(event.pointerId), ...fromCanvas(x, y));
  draw();
  if (performance.now() - lastSent > 20) sendHands();
});
for (const kind of ["pointerup", "pointercancel"]) {
  canvas.addEventListener(kind, (event) => {
    pointers.delete(event.pointerId);
    anchors = hands.slice();
  });
}

// The hands go to the robot at a steady rate, moving or not (a still person is seen too).
setInterval(() => { if (performance.now() - lastSent > 80) sendHands(); }, 100);

$("start").addEventListener("click", () => {
  mode = $("mode").value;
  $("message").textContent = "";
  send({ type: "game", action: "start", mode, model: $("model").value || null });
});
$("stop").addEventListener("click", () => send({ type: "game", action: "stop", mode, model: null }));
$("mode").addEventListener("change", () => { mode = $("mode").value; draw(); });
$("mirror-view").addEventListener("change", draw);

connect();
draw();
