"""Test BVH files: the demonstrator's movements performed by a skeleton.

A standard skeleton (root, spine, chest, neck, head; per side clavicle, upper arm, forearm,
hand and one finger) whose arms reach each hand's target by two-link inverse kinematics, its
joint rotations written as Euler angles by SciPy (an implementation independent of the reader's
forward kinematics). Variants: the joint naming, the size of the person, the unit, the up axis
and the direction the person faces.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from rnnpb.demonstrator import PatternConfig, UserBody, pattern_offsets

NAMINGS = {
    "cmu": {
        "root": "Hips",
        "spine": "Spine",
        "chest": "Chest",
        "neck": "Neck",
        "clavicle": "{Side}Shoulder",
        "upper": "{Side}Arm",
        "fore": "{Side}ForeArm",
        "hand": "{Side}Hand",
        "finger": "{Side}HandIndex1",
    },
    "underscore": {
        "root": "joint_Root",
        "spine": "Spine",
        "chest": "Chest",
        "neck": "Neck",
        "clavicle": "Shoulder_{S}",
        "upper": "UpperArm_{S}",
        "fore": "LowerArm_{S}",
        "hand": "Hand_{S}",
        "finger": "Index_{S}",
    },
    "lower": {
        "root": "pelvis",
        "spine": "spine_01",
        "chest": "spine_02",
        "neck": "neck",
        "clavicle": "{s}_clavicle",
        "upper": "{s}_shoulder",
        "fore": "{s}_elbow",
        "hand": "{s}_wrist",
        "finger": "{s}_index_1",
    },
}
UNIT_PER_M = {"m": 1.0, "cm": 100.0, "mm": 1000.0, "in": 1 / 0.0254}
# Rest skeleton of the standard user (metres): shoulder joints 0.19 m either side of the
# chest, upper arm 0.30 m and forearm 0.32 m (0.62 m, UserBody's arm reach).
HIPS_HEIGHT = 1.0
SPINE, CHEST, NECK, HEAD = 0.2, 0.25, 0.05, 0.2
CLAVICLE, UPPER_OFFSET = np.array([0.02, 0.05, 0.0]), 0.17
UPPER_ARM, FOREARM = 0.30, 0.32


def demonstrator_hands(pattern: str, times: np.ndarray, period: float) -> np.ndarray:
    """The demonstrator's ideal hands (n, 2, 3), robot frame, at ``times`` seconds."""
    config = PatternConfig()
    theta = 2 * np.pi * np.asarray(times) / period
    return config.body.hand_centres + pattern_offsets(pattern, theta, config)


def _turn(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotation matrices (n, 3, 3) turning unit ``u`` (3,) onto unit vectors ``v`` (n, 3)."""
    return np.stack([Rotation.align_vectors(target[None], u[None])[0].as_matrix() for target in v])


def write_bvh(
    path: Path,
    hands: np.ndarray,
    frame_time: float,
    *,
    naming: str = "cmu",
    size: float = 1.0,
    unit: str = "cm",
    up: str = "y",
    heading_deg: float = 0.0,
    drift: float = 0.0,
) -> Path:
    """Write a BVH file of a person of ``size`` (1: the standard user) whose hands make the
    movement ``hands`` (n, 2, 3) (robot frame, relative to the standard user's shoulders).

    ``up`` ``"y"`` or ``"z"``; ``heading_deg`` turns the person about the up axis; ``drift``
    (m/s) moves the person sideways as they go.
    """
    names = NAMINGS[naming]
    k = UNIT_PER_M[unit]

    def name(part: str, side: str = "") -> str:
        return names[part].format(Side=side.capitalize(), S=side[:1].upper(), s=side[:1])

    # The person's frame: Y up, facing +Z, left +X (right-handed, as BVH).
    body = UserBody()
    n = len(hands)
    relative = (hands - body.shoulders) * size  # robot frame
    # robot (x, y, z) -> person: forward = -x, left = -y, up = z -> world (left, up, forward)
    targets = np.stack([-relative[..., 1], relative[..., 2], -relative[..., 0]], axis=-1)
    joints_local: dict[str, np.ndarray] = {}
    for index, side, sign in ((0, "left", 1.0), (1, "right", -1.0)):
        a, b = UPPER_ARM * size, FOREARM * size
        d = targets[:, index]
        distance = np.linalg.norm(d, axis=-1, keepdims=True)
        assert np.all(distance < a + b), "a target out of the arm's reach"
        direction = d / distance
        pole = np.array([0.0, -1.0, -0.3])
        normal = pole - (direction @ pole)[:, None] * direction
        normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
        cos_alpha = (a**2 + distance**2 - b**2) / (2 * a * distance)
        alpha = np.arccos(np.clip(cos_alpha, -1, 1))
        elbow = a * (np.cos(alpha) * direction + np.sin(alpha) * normal)
        rest = np.array([sign, 0.0, 0.0])
        upper = _turn(rest, elbow / a)
        fore = _turn(rest, (d - elbow) / b)
        joints_local[name("upper", side)] = upper
        joints_local[name("fore", side)] = np.einsum("nji,njk->nik", upper, fore)
    root_turn = Rotation.from_euler("y", heading_deg, degrees=True)
    if up == "z":
        root_turn = Rotation.from_euler("x", 90, degrees=True) * root_turn
    elif up != "y":
        raise ValueError(up)
    times = np.arange(n) * frame_time
    root_position = np.stack([drift * times, np.full(n, HIPS_HEIGHT * size), np.zeros(n)], axis=-1)
    root_position = root_turn.apply(root_position)

    lines = ["HIERARCHY"]
    channels: list[str] = []  # joint name per rotation triple, "root" for the root's six

    def offset(vector) -> str:
        return "OFFSET " + " ".join(f"{v * k * size:.6f}" for v in vector)

    def joint(kind: str, label: str, vector, depth: int, children=(), end=None) -> None:
        pad = "\t" * depth
        lines.append(f"{pad}{kind} {label}")
        lines.append(f"{pad}{{")
        lines.append(f"{pad}\t{offset(vector)}")
        if kind == "ROOT":
            lines.append(
                f"{pad}\tCHANNELS 6 Xposition Yposition Zposition Xrotation Yrotation Zrotation"
            )
        else:
            lines.append(f"{pad}\tCHANNELS 3 Zrotation Xrotation Yrotation")
        channels.append(label)
        for child in children:
            child(depth + 1)
        if end is not None:
            lines.append(f"{pad}\tEnd Site")
            lines.append(f"{pad}\t{{")
            lines.append(f"{pad}\t\t{offset(end)}")
            lines.append(f"{pad}\t}}")
        lines.append(f"{pad}}}")

    def arm(side: str, sign: float):
        def finger(depth):
            joint(
                "JOINT", name("finger", side), [sign * 0.05, 0, 0], depth, end=[sign * 0.03, 0, 0]
            )

        def hand(depth):
            joint("JOINT", name("hand", side), [sign * FOREARM, 0, 0], depth, children=[finger])

        def fore(depth):
            joint("JOINT", name("fore", side), [sign * UPPER_ARM, 0, 0], depth, children=[hand])

        def upper(depth):
            joint("JOINT", name("upper", side), [sign * UPPER_OFFSET, 0, 0], depth, children=[fore])

        def clavicle(depth):
            joint("JOINT", name("clavicle", side), CLAVICLE * [sign, 1, 1], depth, children=[upper])

        return clavicle

    def neck(depth):
        joint("JOINT", name("neck"), [0, NECK, 0], depth, end=[0, HEAD, 0])

    def chest(depth):
        joint(
            "JOINT",
            name("chest"),
            [0, CHEST, 0],
            depth,
            children=[neck, arm("left", 1.0), arm("right", -1.0)],
        )

    def spine(depth):
        joint("JOINT", name("spine"), [0, SPINE, 0], depth, children=[chest])

    joint("ROOT", name("root"), [0, 0, 0], 0, children=[spine])
    root_euler = root_turn.as_euler("XYZ", degrees=True)
    identity = np.zeros((n, 3))
    columns = []
    for label in channels:
        if label == name("root"):
            columns.append(root_position * k)
            columns.append(np.broadcast_to(root_euler, (n, 3)))
        elif label in joints_local:
            columns.append(Rotation.from_matrix(joints_local[label]).as_euler("ZXY", degrees=True))
        else:
            columns.append(identity)
    motion = np.concatenate(columns, axis=1)
    lines += ["MOTION", f"Frames: {n}", f"Frame Time: {frame_time:.8f}"]
    lines += [" ".join(f"{v:.6f}" for v in row) for row in motion]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path
