"""Safe retargeting, measured: how far from the requested hands, how clear of the body, and at
what cost per step — the chosen method (mink's differential IK with collision avoidance,
:mod:`rnnpb.robot._retarget`) against extending the paper's inverse kinematics by the simplest
safe rule (walk from the plain IK posture back toward the last safe posture, along the joint-
space line, to the last clear point: bisection).

Run: ``.venv/bin/python benchmarks/retargeting.py [--bvh FILE[,FILE…]] [--dt 0.4]``

It prints one row per person posture (hands at the hips, crossed in front of the chest, above
the head, behind the back, resting low, clapping at the chest) and, with ``--bvh``, the figures
over every step of a motion capture retargeted as ``rnnpb record bvh:`` does.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from rnnpb.demonstrator import MirrorMapping, UserBody
from rnnpb.robot import (
    RETARGET_CLEARANCE,
    SelfCollision,
    forward_kinematics,
    inverse_kinematics,
    retarget,
)
from rnnpb.robot._retarget import REST_POSTURE

PERSON = {
    "hands at the hips": [[0.97, -0.17, 0.50], [0.97, 0.17, 0.50]],
    "crossed in front of the chest": [[0.78, 0.10, 0.78], [0.78, -0.10, 0.80]],
    "above the head": [[0.95, -0.15, 1.50], [0.95, 0.15, 1.50]],
    "behind the back": [[1.15, -0.08, 0.62], [1.15, 0.08, 0.62]],
    "resting low": [[0.92, -0.20, 0.40], [0.92, 0.20, 0.40]],
    "clapping at the chest": [[0.80, 0.0, 0.85], [0.80, 0.0, 0.85]],
}


def walk_back(targets: np.ndarray, collision: SelfCollision) -> np.ndarray:
    """The alternative: the plain IK posture, or the last clear point on the way to it from the
    last safe posture (from the rest posture at the start)."""
    plain = inverse_kinematics(targets).joints
    out = np.empty_like(plain)
    safe = np.array(REST_POSTURE)
    for t, q in enumerate(plain):
        if collision.clearance(q) >= RETARGET_CLEARANCE:
            safe = q
        else:
            lo, hi = 0.0, 1.0  # fraction of the way from safe to q; lo is clear
            for _ in range(12):
                mid = 0.5 * (lo + hi)
                if collision.clearance(safe + mid * (q - safe)) >= RETARGET_CLEARANCE:
                    lo = mid
                else:
                    hi = mid
            safe = safe + lo * (q - safe)
        out[t] = safe
    return out


def measure(targets: np.ndarray, dt: float, collision: SelfCollision) -> dict[str, dict]:
    rows = {}
    start = time.perf_counter()
    chosen = retarget(targets, dt).joints
    rows["mink (chosen)"] = {"seconds": time.perf_counter() - start, "joints": chosen}
    start = time.perf_counter()
    alternative = walk_back(targets, collision)
    rows["walk back"] = {"seconds": time.perf_counter() - start, "joints": alternative}
    plain = inverse_kinematics(targets)
    rows["plain IK (unsafe)"] = {"seconds": float("nan"), "joints": plain.joints}
    for row in rows.values():
        reached, _ = forward_kinematics(row["joints"])
        row["residual"] = np.linalg.norm(reached - targets, axis=-1)
        row["clearance"] = np.array([collision.clearance(q) for q in row["joints"]])
        row["colliding"] = int(sum(collision.collides(q) for q in row["joints"]))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--bvh", help="motion capture file(s) to retarget, comma-separated")
    parser.add_argument("--time-scale", type=float, default=1.0)
    parser.add_argument("--dt", type=float, default=0.4)
    args = parser.parse_args()
    collision = SelfCollision()
    mapping = MirrorMapping(UserBody(), dt=args.dt)
    retarget(mapping.robot_hand_targets(np.array([PERSON["resting low"]])), args.dt)  # warm up
    print("posture | method | hand distance to target (cm, left/right) | clearance (cm)")
    for name, hands in PERSON.items():
        targets = mapping.robot_hand_targets(np.array([hands]))
        for method, row in measure(targets, args.dt, collision).items():
            print(
                f"{name} | {method} | {row['residual'][0, 0] * 100:.1f} / "
                f"{row['residual'][0, 1] * 100:.1f} | {row['clearance'][0] * 100:.1f}"
            )
    if args.bvh:
        from rnnpb.mocap import capture_stream

        hands = capture_stream(args.bvh.split(","), dt=args.dt, time_scale=args.time_scale).hands
        targets = mapping.robot_hand_targets(hands)
        targets = targets[np.isfinite(targets).all(axis=(1, 2))]
        print(f"\n{args.bvh}: {len(targets)} steps at dt {args.dt}")
        print("method | colliding steps | median / p95 hand distance (cm) | ms per step")
        for method, row in measure(targets, args.dt, collision).items():
            r = row["residual"].ravel() * 100
            print(
                f"{method} | {row['colliding']} | {np.median(r):.1f} / "
                f"{np.percentile(r, 95):.1f} | {row['seconds'] / len(targets) * 1000:.2f}"
            )


if __name__ == "__main__":
    main()
