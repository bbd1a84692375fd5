// The teaching panel (docs/dashboard.md, "Teaching"): what the novelty detector says,
// "recording a new movement (cycle 2 of 4)", the consolidation's progress, the result and its
// rename, the kept episodes and the model versions, Confirm and Undo.
import { $, dash, el } from "./dash.js";
import { onError, send, showError } from "./connection.js";

// The movement the person confirmed, from their click until the server's answer: the panel
// says at once that it is being learned, never asks again.
let confirming = null;
onError(() => { confirming = null; });

const NOVELTY_WORDS = { familiar: "a learned pattern", novel: "a new movement",
  unstructured: "no repeating pattern", still: "hands still" };
export function showTeachingStatus(status, step) {
  const teaching = dash.state && dash.state.teaching;
  if (!status || !teaching) return;
  const job = status.consolidation;
  if (confirming && (teaching.consolidating || teaching.result !== confirming.result)) {
    confirming = null;
  }
  let phase = status.phase, badge, text = status.text || "", progress = null, note = "";
  if (confirming && !job) {
    phase = "consolidating";
    badge = "consolidating";
    text = `learning ${confirming.pattern}: starting — the robot keeps moving`;
  } else if (job && job.state === "done") {
    // Learned; the new version's network is compiled before it takes over (seconds).
    phase = "consolidating";
    badge = "consolidating";
    text = "learned — making the new version ready (compiling its network); the robot keeps "
      + "moving";
    progress = 1;
    note = `${Math.round(job.seconds)} s`;
  } else if (job) {
    phase = "consolidating";
    badge = "consolidating";
    const learning = (teaching.learning || []).join(", ") || "the kept movement";
    text = `learning ${learning} in the background — the robot keeps moving`;
    progress = job.total ? job.iteration / job.total : null;
    note = `${Math.round(job.seconds)} s${job.total ? ` · iteration ${job.iteration} of `
      + `${job.total}` : ""}`;
  } else if (phase === "recording") {
    badge = "recording";
    progress = Math.min(status.cycles, status.episode_cycles) / status.episode_cycles;
    note = `${Math.min(status.cycles, status.episode_cycles)} of ${status.episode_cycles} whole `
      + "cycles";
  } else if (phase === "kept") {
    badge = "kept";
    text = `new movement kept in the short-term memory${seenText(teaching)}`;
  } else if (phase === "off") {
    badge = "off";
    text = teaching.available ? "learning is off: nothing is kept"
      : (teaching.unavailable || status.text || "");
  } else {
    const novelty = step ? step.novelty : "";
    phase = novelty === "novel" ? "novel" : novelty === "familiar" ? "familiar" : "watching";
    badge = "watching";
    // Recording can start only when nothing waits (no kept movement before Confirm, no
    // learning, no swap of the model) and learning is on.
    const canRecord = teaching.available && teaching.mode !== "off" && !job
      && !teaching.waiting && !(dash.state && dash.state.loading);
    text = !step ? "start the robot and perform a movement"
      : NOVELTY_WORDS[novelty] ? `the robot sees ${NOVELTY_WORDS[novelty]}`
        + (novelty === "novel" && canRecord ? " — keep performing it: whole cycles are counted"
          : "")
        : "the robot is not sure yet what it sees";
    if (step) text += seenText(teaching);
  }
  const box = $("teach-phase");
  box.dataset.phase = phase;
  $("teach-badge").textContent = badge;
  $("teach-text").textContent = text;
  const bar = $("teach-progress");
  if (progress === null) bar.removeAttribute("value"); else bar.value = progress;
  bar.hidden = !(phase === "recording" || phase === "consolidating");
  $("teach-progress-text").textContent = note;
  dash.teachPhase = phase;
  const canConfirm = teaching.available && !job && !confirming && !!teaching.asks;
  $("teach-confirm").disabled = !dash.connected || !canConfirm;
}

// How many performances the kept movements have: a new movement is learned from two (Confirm
// learns it from what was seen).
const TIMES = { 1: "once", 2: "twice" };
// Only the movement Confirm would learn (teaching.asks) is offered to it.
function seenText(teaching) {
  const seen = Object.entries(teaching.seen || {});
  if (!seen.length || confirming) return "";
  const needed = teaching.performances || 2;
  const confirm = (pattern) => teaching.mode === "confirm" && pattern === teaching.asks;
  return " — " + seen.map(([pattern, n]) => `${pattern} seen ${TIMES[n] || `${n} times`}: `
    + (n < needed ? "show it again to learn it"
      + (confirm(pattern) ? " (or press Confirm to learn it from one)" : "")
      : confirm(pattern) ? "learn it now? press Confirm"
        : teaching.mode === "confirm" ? "waits to be confirmed" : "learning it"))
    .join("; ");
}

export function showTeaching(state) {
  const teaching = state.teaching;
  if (!teaching) return;
  if (document.activeElement !== $("teach-mode")) $("teach-mode").value = teaching.mode;
  const result = $("teach-result");
  result.textContent = teaching.result || "";
  result.hidden = !teaching.result;
  const failure = $("teach-failure");
  failure.textContent = teaching.failure ? `${teaching.failure} — the running model stays` : "";
  failure.hidden = !teaching.failure;
  $("teach-undo").disabled = !dash.connected || !teaching.can_undo;
  // Undo goes back to the version run before this one (an undone one is not gone back to).
  const versions = teaching.versions || [];
  const back = versions.slice(0, versions.findIndex((v) => v.running))
    .filter((v) => !v.undone).at(-1);
  $("teach-undo").title = teaching.can_undo && back ? `go back to ${back.name}`
    : "nothing to undo: the robot runs its first version";
  // Rename: the patterns teaching learned, and the kept movements not learned yet.
  const names = [...(teaching.taught || []), ...(teaching.episodes || [])
    .filter((e) => e.status === "kept").map((e) => e.pattern)];
  const unique = [...new Set(names)];
  const select = $("rename-pattern");
  if (select.dataset.names !== JSON.stringify(unique)) {
    select.dataset.names = JSON.stringify(unique);
    select.replaceChildren(...unique.map((n) => new Option(n, n)));
  }
  $("rename").hidden = unique.length === 0;
  const rows = (teaching.episodes || []).map((e) => el("tr", {},
    el("td", {}, `#${e.id}`), el("td", {}, e.pattern),
    el("td", { className: `status-${e.status}` }, e.status),
    el("td", {}, `${e.n_cycles} cycles, ${e.n_steps} steps`),
    el("td", {}, e.merged ? `another performance of #${e.merged}` : ""), el("td", {}, e.source),
    el("td", {}, e.when)));
  $("teach-episodes").replaceChildren(rows.length
    ? el("tr", {}, ...["", "pattern", "status", "movement", "merged", "from", "kept"].map((h) =>
      el("th", {}, h)))
    : el("tr", {}, el("td", {}, "nothing kept yet")), ...rows);
  // Every version the model list offers, the one running marked as there.
  $("teach-versions").replaceChildren(...(teaching.versions || []).map((v) => {
    const item = el("li", { className: v.running ? "running" : v.undone ? "undone" : "" },
      v.name, el("small", {}, ` — ${v.patterns.join(", ")}${v.running ? " (running)"
        : v.undone ? " (undone; choose it in Model to run it again)" : ""}`));
    item.dataset.name = v.name;
    return item;
  }));
  const asks = teaching.asks || "";
  $("teach-confirm").textContent = `✓ Confirm: learn ${asks || "it"}`;
  $("teach-confirm").title = asks ? `learn ${asks} into a new model version (a movement seen `
    + "once is learned from that one performance); other kept movements stay kept"
    : "nothing kept to learn: perform a new movement first";
  $("teach-folder").textContent = [teaching.folder,
    teaching.memory ? `Short-term memory: ${teaching.memory}.` : ""].filter(Boolean).join(". ");
  showTeachingStatus(teaching.status, dash.lastStep && dash.run === state.run
    ? dash.lastStep : null);
}

$("teach-mode").onchange = (e) => send({ type: "teach_mode", mode: e.target.value });
$("teach-confirm").onclick = () => {
  const teaching = dash.state && dash.state.teaching;
  const pattern = teaching && teaching.asks;
  if (!pattern) return;
  if (send({ type: "teach", action: "confirm", pattern })) {
    confirming = { pattern, result: teaching.result };
    showTeachingStatus(teaching.status, dash.lastStep);
  }
};
$("teach-undo").onclick = () => send({ type: "teach", action: "undo" });
$("rename-apply").onclick = () => {
  const name = $("rename-name").value.trim();
  const pattern = $("rename-pattern").value;
  if (!name || !pattern) { showError("rename: choose a pattern and type its new name"); return; }
  if (send({ type: "rename", pattern, name })) $("rename-name").value = "";
};
