// How the other hand follows the one a single pointer drags, shared by the dashboard's
// pointer panel and the mirror game: one mouse can then make every two-hand pattern.

// Per axis of the robot camera's view (Y across, Z up): mirror reflects left-right, parallel
// copies, opposite phase is half a turn about the centre; still leaves the other hand.
export const COUPLINGS = { mirror: [-1, 1], parallel: [1, 1], opposite: [-1, -1], still: null };
export const COUPLING_NAMES = {
  mirror: "mirror (left–right)", parallel: "parallel (the same way)",
  opposite: "opposite phase (half a turn)", still: "still",
};
export const DEFAULT_COUPLING = "mirror";  // the movement people make first

// `hands` (lhy lhz rhy rhz) with hand `index` at (y, z) and, with `coupling`, the other hand
// moved from where it was when the drag began (`anchors`, both hands then) as the dragged one
// moved from its own: the other hand does not drift over many drags.
export function follow(hands, anchors, index, y, z, coupling) {
  const out = hands.slice();
  out[2 * index] = y;
  out[2 * index + 1] = z;
  const sign = COUPLINGS[coupling];
  if (!sign || !anchors) return out;
  const other = 1 - index;
  const clip = (v) => Math.min(1, Math.max(0, v));
  out[2 * other] = clip(anchors[2 * other] + sign[0] * (y - anchors[2 * index]));
  out[2 * other + 1] = clip(anchors[2 * other + 1] + sign[1] * (z - anchors[2 * index + 1]));
  return out;
}
