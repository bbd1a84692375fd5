// The mirror game (docs/dashboard.md). DOM text only through textContent; no inline code.
const $ = (id) => document.getElementById(id);
const canvas = $("view");
const ctx = canvas.getContext("2d");
const REST = [0.62, 0.55, 0.38, 0.55]; // lhy lhz rhy rhz: where your hands start
let hands = REST.slice();
let robotA = null;
let robotB = null;
let mode = "person";
let dragging = null; // index of the hand being dragged (0 left, 1 right)
let ws = null;

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
  $("found").textContent = step.found.length
    ? `${step.found.length} of ${step.learned}: ${step.found.join(", ")}` : `none yet (of ${step.learned})`;
  $("leader").textContent = step.last_leader || "–";
  $("time").textContent = `${step.time_s.toFixed(1)} s (step ${step.step})`;
  draw();
}

function toCanvas(y, z) { return [y * canvas.width, (1 - z) * canvas.height]; }
function fromCanvas(x, y) {
  return [Math.min(1, Math.max(0, x / canvas.width)), Math.min(1, Math.max(0, 1 - y / canvas.height))];
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
    : "the robot (orange) and you (blue), as the robot's camera sees you", 8, 16);
  for (const i of [0, 1]) dot(robotA, i, "#e8772e", i ? "R" : "L");
  if (mode === "robots") for (const i of [0, 1]) dot(robotB, i, "#2e9e55", i ? "R" : "L", true);
  else for (const i of [0, 1]) dot(hands, i, "#2f6fdf", i ? "R" : "L", true);
}

function nearest(px, py) {
  let best = 0;
  let bestDistance = Infinity;
  for (const i of [0, 1]) {
    const [x, y] = toCanvas(hands[2 * i], hands[2 * i + 1]);
    const d = Math.hypot(x - px, y - py);
    if (d < bestDistance) { best = i; bestDistance = d; }
  }
  return best;
}

function moveHand(index, y, z) {
  const other = 1 - index;
  const dy = y - hands[2 * index];
  const dz = z - hands[2 * index + 1];
  hands[2 * index] = y;
  hands[2 * index + 1] = z;
  const coupling = $("coupling").value;
  const sign = { together: [1, 1], mirrored: [-1, 1], opposite: [-1, -1] }[coupling];
  if (sign) {
    hands[2 * other] = Math.min(1, Math.max(0, hands[2 * other] + sign[0] * dy));
    hands[2 * other + 1] = Math.min(1, Math.max(0, hands[2 * other + 1] + sign[1] * dz));
  }
}

function position(event) {
  const rect = canvas.getBoundingClientRect();
  return [(event.clientX - rect.left) * canvas.width / rect.width,
    (event.clientY - rect.top) * canvas.height / rect.height];
}

canvas.addEventListener("pointerdown", (event) => {
  const [x, y] = position(event);
  dragging = nearest(x, y);
  canvas.setPointerCapture(event.pointerId);
});
canvas.addEventListener("pointermove", (event) => {
  if (dragging === null) return;
  const [x, y] = position(event);
  moveHand(dragging, ...fromCanvas(x, y));
  draw();
});
canvas.addEventListener("pointerup", () => { dragging = null; });

// The hands go to the robot at a steady rate, moving or not (a still person is seen too).
setInterval(() => { if (mode === "person") send({ type: "game_hands", hands: hands.map((v) => +v.toFixed(5)) }); }, 100);

$("start").addEventListener("click", () => {
  mode = $("mode").value;
  $("message").textContent = "";
  send({ type: "game", action: "start", mode, model: $("model").value || null });
});
$("stop").addEventListener("click", () => send({ type: "game", action: "stop", mode, model: null }));
$("mode").addEventListener("change", () => { mode = $("mode").value; draw(); });

connect();
draw();
