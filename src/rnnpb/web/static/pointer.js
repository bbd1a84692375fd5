// The pointer panel: the robot's camera view of you, where a mouse, pen or fingers drag the
// two markers (your hands); the robot perceives their latest positions each step.
import { $, BLUE, RED, dash } from "./dash.js";
import { send } from "./connection.js";
import { follow } from "./hands.js";

// The panel is the robot's camera view: x = Y (0 left .. 1 right), y = 1 - Z.
const pointerCanvas = $("pointer");
const grabs = new Map();   // pointerId -> hand index (0 left/red, 1 right/blue)
let anchors = null;        // both hands where the one dragging pointer took them
let pendingSend = false;

// The dragged hand at (y, z); with one pointer, the other hand as "Other hand" says (two
// fingers each drag their own).
function moveHand(hand, y, z) {
  const coupling = grabs.size === 1 ? $("other-hand").value : "still";
  dash.markers = follow(dash.markers, anchors, hand, y, z, coupling);
}

function panelToHand(e) {
  const rect = pointerCanvas.getBoundingClientRect();
  const y = Math.min(1, Math.max(0, (e.clientX - rect.left) / rect.width));
  const z = Math.min(1, Math.max(0, 1 - (e.clientY - rect.top) / rect.height));
  return [y, z];
}
export function sendMarkers() {
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
  anchors = dash.markers.slice();
  moveHand(best, y, z);
  sendMarkers();
  drawPointerPanel();
});
pointerCanvas.addEventListener("pointermove", (e) => {
  if (!grabs.has(e.pointerId)) return;
  const hand = grabs.get(e.pointerId);
  const [y, z] = panelToHand(e);
  moveHand(hand, y, z);
  sendMarkers();
  drawPointerPanel();
});
const release = (e) => { grabs.delete(e.pointerId); anchors = dash.markers.slice(); };
pointerCanvas.addEventListener("pointerup", release);
pointerCanvas.addEventListener("pointercancel", release);

export function drawPointerPanel() {
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

// What teaching does with the pointer's movement, said where the person is looking: a new
// movement being recorded, or kept (never silently: a movement made with one hand while
// trying a two-hand pattern is kept as a new one).
export function showPointerNote() {
  const state = dash.state, step = dash.lastStep;
  const note = $("pointer-note");
  const teaching = state && state.teaching;
  if (!teaching || state.mode !== "pointer" || !teaching.available) { note.textContent = ""; return; }
  const status = (step && step.teaching) || {};
  const kept = (teaching.episodes || []).find((e) => e.status === "kept" && e.source === "pointer");
  const oneHand = $("other-hand").value === "still" ? " (one hand moved, the other held still)" : "";
  if (status.phase === "recording") {
    note.textContent = "The robot sees a new movement and is recording it "
      + `(${Math.min(status.cycles, status.episode_cycles)} of ${status.episode_cycles} whole `
      + "cycles): see Teach it a new movement, below.";
  } else if (kept) {
    note.textContent = `Kept as a new movement, ${kept.pattern}${oneHand}: Confirm in Teach it `
      + "a new movement, below, learns it. To perform a learned two-hand pattern, let Other "
      + "hand move the second hand.";
  } else note.textContent = "";
}
