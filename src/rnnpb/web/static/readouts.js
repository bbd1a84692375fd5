// The readouts under the robot: what the robot says it sees (a learned pattern only when it
// is confident, else "not sure" or "new movement": rnnpb.model.recognition), the confidence
// per learned pattern, the step, the prediction error, who performs, and the routine level.
import { $, dash, describe, el, fmt } from "./dash.js";

dash.readout = (step) => readout(step);  // what the readout says of a step (tests)
export function readout(step) {
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

// The readouts under the robot: the last step's, marked as such while stopped.
export function showReadouts(step) {
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
    : step.mode === "pointer" ? "you (pointer)" : "you (webcam)";
}
export function clearReadouts() {
  for (const id of ["nearest", "pred-error", "truth"]) $(id).textContent = "—";
  $("step").textContent = "0";
  $("nearest-distance").textContent = "";
  $("readouts-note").textContent = "";
}
export function showReadoutsState(state) {
  const box = document.querySelector(".recognised");
  const stale = !state.running && dash.lastStep !== null;
  box.classList.toggle("stale", stale);
  $("readouts-note").textContent = state.loading ? "loading another model…"
    : stale ? `stopped: these are the values of step ${dash.lastStep.step}` : "";
}

// The routine level (docs/routines.md), when the server was given routine files: the routine
// recognised and the movement it expects next (a line under the readouts, made here so that
// the page's markup stays as it is; no line when the server has no routine file).
export function showRoutine(step) {
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
