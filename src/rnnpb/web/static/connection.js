// The one WebSocket to the server's shared session: what is sent, what is refused while
// disconnected, and the red box of problems under the toolbar.
import { $, dash, el } from "./dash.js";

let ws = null;
// `handlers`: a function per message type (state, history, step, frame); `onChange()` when
// the connection opens or closes.
export function connect(handlers, onChange) {
  const proto = location.protocol === "https:" ? "wss:" : "ws:";
  ws = new WebSocket(`${proto}//${location.host}/ws`);
  ws.onopen = () => { dash.connected = true; onChange(); };
  ws.onclose = () => {
    dash.connected = false;
    setControlsEnabled(false);
    onChange();
    setTimeout(() => connect(handlers, onChange), 1000);
  };
  ws.onmessage = (event) => {
    const message = JSON.parse(event.data);
    if (message.type === "error") showError(message.message);
    else if (Object.hasOwn(handlers, message.type)) handlers[message.type](message);
  };
}
// A command sent while disconnected would be lost: say so instead (the controls are
// disabled then, this covers scripted sends and the moment the connection drops).
export function send(message) {
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
export function setControlsEnabled(enabled) {
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
let transientTimer = null;
const listeners = [];
// `listener(text)` hears of every error shown (the webcam panel repeats a camera's).
export function onError(listener) { listeners.push(listener); }
export function showError(text) {
  dash.awaitingAnswer = false;
  dash.errors.push(text);
  transientError = text;
  clearTimeout(transientTimer);
  transientTimer = setTimeout(() => { transientError = null; showProblems(); }, 8000);
  showProblems();
  for (const listener of listeners) listener(text);
}
// A state answered the command: its error, if any, has gone.
export function answered() {
  if (dash.awaitingAnswer) { dash.awaitingAnswer = false; transientError = null; }
}
function standingProblems(state) {
  if (!state) return [];
  return [...new Set([state.model_error, state.error, state.recording_error].filter(Boolean))];
}
export function showProblems() {
  const problems = standingProblems(dash.state);
  if (transientError && !problems.includes(transientError)) problems.unshift(transientError);
  const box = $("error");
  box.replaceChildren(...problems.map((p) => el("div", {}, p)));
  box.hidden = problems.length === 0;
}
