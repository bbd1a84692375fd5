// The time plots (perceived and predicted hands, the joint angles) and the loop's timing
// table, drawn by hand on <canvas>: a few line plots are not worth a plotting library.
import { $, BLUE, HISTORY, RED, dash, el, fmt } from "./dash.js";

const JOINT_COLORS = ["#7b3fb5", "#d98a00", "#1b9e77", "#555"];

export function setupCanvas(canvas) {
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

export function drawPlots() {
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
  drawTimings();
}

export function jointLegend() {
  const names = ["shoulder pitch", "shoulder roll", "shoulder yaw", "elbow pitch"];
  // Colours set through the style object: the CSP refuses style attributes in markup.
  $("joint-legend").replaceChildren(...names.flatMap((n, i) => {
    const swatch = el("span", { className: "line" });
    swatch.style.background = JOINT_COLORS[i];
    return [swatch, `${n} `];
  }), "— solid: left arm, dashed: right arm");
}
