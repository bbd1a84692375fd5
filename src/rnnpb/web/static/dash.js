// What every part of the dashboard shares: the page's knowledge (`dash`, also
// window.rnnpbDashboard for tests and the console), and small helpers.
// Text from the server (model and pattern names come from files, errors echo clients) is only
// ever set as textContent, never parsed as HTML; the page's CSP allows no inline script.

export const RED = "#d63a3a", BLUE = "#2f6fd6";
export const HISTORY = 120;               // steps kept for the plots (the server replays as many)
export const PATTERN_NAMES = {
  "1": "horizontal swing, opposite phase", "2": "vertical swing, in phase",
  "3": "rotation, opposite phase", "4": "rotation, in phase",
};

export const $ = (id) => document.getElementById(id);
// A movement's description (the paper's patterns, the demonstrator's new shapes); any other
// name (even "__proto__") has none.
export const describe = (p) => {
  const more = (dash.state && dash.state.movement_descriptions) || {};
  if (Object.hasOwn(PATTERN_NAMES, p)) return PATTERN_NAMES[p];
  return Object.hasOwn(more, p) ? more[p] : "";
};
// An element with text children only: strings become text nodes, never markup.
export function el(tag, props = {}, ...children) {
  const node = document.createElement(tag);
  Object.assign(node, props);
  node.append(...children.map((c) => (c instanceof Node ? c : String(c))));
  return node;
}
export const fmt = (v, digits = 3) => (v === null || v === undefined || Number.isNaN(v)) ? "—"
  : Number(v).toFixed(digits);

// Shared with tests and the console: what the page knows.
export const dash = window.rnnpbDashboard = {
  connected: false, state: null, lastStep: null, steps: 0, history: [], errors: [],
  rendered3d: 0, markers: null, run: null, refusedSends: 0, replayed: 0,
};
