// The toolbar: the model list, Start, Stop, Reset, the step time and the status line.
import { $, dash } from "./dash.js";
import { send, showError } from "./connection.js";

// The model list, and the one chosen: while a model loads, the one being loaded.
export function showModels(state) {
  const select = $("model");
  const names = [...select.options].map((o) => o.value);
  if (JSON.stringify(names) !== JSON.stringify(state.models)) {
    select.replaceChildren();
    for (const name of state.models) select.add(new Option(name, name));
  }
  const shown = state.loading_model || state.model;
  if (shown) select.value = shown;
}


export function updateStatus() {
  const el = $("status");
  showStatus(el);
  el.title = el.textContent;  // the line may be cut short on a narrow toolbar
}
function showStatus(el) {
  const s = dash.state;
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

// Start is on only when there is a model to run and it is not running or loading.
export function showToolbar(state) {
  showModels(state);
  if (document.activeElement !== $("dt")) $("dt").value = state.dt;
  const canStart = !state.running && !state.loading && !!state.model;
  $("start").disabled = !canStart;
  $("start").title = state.model ? "" : `no model loaded${state.model_error ? `: ${state.model_error}` : ""}`;
  $("stop").disabled = !state.running;
}

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
