// Who drives the robot: the tabs (demonstrator, pointer, webcam), the demonstrator's
// movements, and the webcam's controls and image.
import { $, PATTERN_NAMES, dash, describe, el } from "./dash.js";
import { onError, send } from "./connection.js";
import { sendMarkers } from "./pointer.js";

const shownMode = { server: null, view: null };
export function showMode(mode) {
  shownMode.view = mode;
  document.querySelectorAll(".tab").forEach((tab) =>
    tab.classList.toggle("active", tab.dataset.mode === mode));
  document.querySelectorAll(".mode-body").forEach((body) =>
    body.classList.toggle("active", body.dataset.mode === mode));
}

// The mode the server runs and what the panels show of it. Another tab (or a successful
// switch) changed the mode: show it. A failed switch to the webcam leaves the webcam panel
// shown, with the reason.
export function showDrive(state) {
  if (state.mode !== shownMode.server) { shownMode.server = state.mode; showMode(state.mode); }
  if (state.mode === "webcam") $("camera-message").textContent = "";
  if (state.perception && document.activeElement !== $("perception")) {
    $("perception").value = state.perception;
  }
  $("frame").hidden = state.mode !== "webcam";
  buildPatternButtons(state);
}

// The demonstrator performs patterns 1-4 only: those are its buttons, each saying whether the
// model learned it. Learned patterns it cannot perform are listed, for the pointer or webcam.
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
      + "the pointer or in front of the webcam."
    : "");
}

export function onFrame(message) {
  const img = $("frame");
  img.src = `data:image/jpeg;base64,${message.jpeg}`;
  img.hidden = false;
}

// A camera that cannot be opened: the webcam panel says why, and who still drives.
onError((text) => {
  if (!/camera/i.test(text)) return;
  const mode = dash.state ? dash.state.mode : "demonstrator";
  $("camera-message").textContent = `${text}. The robot is still driven by the ${mode}; `
    + "connect a camera or try another index.";
});
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
