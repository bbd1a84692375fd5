// rnnpb dashboard: one WebSocket to the server's shared session; each part of the page is a
// module of its own, drawn here from the server's state and step messages.
import { $, HISTORY, dash } from "./dash.js";
import { answered, connect, setControlsEnabled, showProblems } from "./connection.js";
import { showDrive, onFrame } from "./drive.js";
import { drawPB, showSafety } from "./pbspace.js";
import { drawPlots, jointLegend } from "./plots.js";
import { drawPointerPanel, showPointerNote } from "./pointer.js";
import { clearReadouts, showReadouts, showReadoutsState, showRoutine } from "./readouts.js";
import { robotView } from "./robot3d.js";
import { showTeaching, showTeachingStatus } from "./teaching.js";
import { showToolbar, updateStatus } from "./toolbar.js";

function drawAll() {
  drawPlots();
  drawPB();
}

function onState(state) {
  dash.state = state;
  answered();
  showDrive(state);
  if (state.rest_hands && !dash.markers) {
    dash.markers = state.rest_hands.slice();
    drawPointerPanel();
  }
  if (state.run !== dash.run) startRun(state.run);
  setControlsEnabled(true);
  showToolbar(state);
  showReadoutsState(state);
  showTeaching(state);
  showPointerNote();
  showProblems();
  updateStatus();
  drawAll();
  showSafety(dash.lastStep);
  showRoutine(dash.lastStep);
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
  drawAll();
  drawPointerPanel();
}

function onStep(step) {
  dash.lastStep = step;
  dash.steps += 1;
  dash.history.push(step);
  if (dash.history.length > HISTORY) dash.history.shift();
  robotView.push(step);
  showReadouts(step);
  updateStatus();
  drawAll();
  drawPointerPanel();
  showSafety(step);
  showRoutine(step);
  showTeachingStatus(step.teaching, step);
  showPointerNote();
}

jointLegend();
drawPointerPanel();
setControlsEnabled(false);
drawAll();
connect({ state: onState, history: onHistory, step: onStep, frame: onFrame }, updateStatus);
