// The PB space: the PB's path over the last steps and each learned pattern's PB, in the plane
// through the learned PBs or in raw PB coordinates, with the safety map's learned risk shaded
// under it, and the line that says what guards the robot.
import { $, dash, el } from "./dash.js";
import { setupCanvas } from "./plots.js";

let projection = null;
let projected = null; // the learned PBs the projection was made for
// The plane is made anew for other learned PBs (another model, a version learned).
function projectionFor(mode) {
  const key = JSON.stringify((dash.state && dash.state.pattern_pb) || {});
  if (!projection || projection.mode !== mode || projected !== key) {
    projected = key;
    projection = { mode, ...pbProjection(mode) };
  }
  return projection;
}
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

export function drawPB() {
  const canvas = $("plot-pb"), g = setupCanvas(canvas), w = canvas.width, h = canvas.height;
  const mode = $("pb-projection").value;
  const P = projectionFor(mode);
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
export function showSafety(step) {
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

$("pb-projection").onchange = () => drawPB();
