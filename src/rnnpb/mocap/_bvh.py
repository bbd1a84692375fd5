"""BVH files: a strict reader and the skeleton's forward kinematics in NumPy.

A BVH file (Biovision Hierarchy, what motion-capture studios export) holds a skeleton — joints
in a tree, each with an ``OFFSET`` from its parent and the ``CHANNELS`` the motion drives — and
a ``MOTION`` block: ``Frames: N``, ``Frame Time: T`` seconds and one line of channel values per
frame, in the order the channels appear in the hierarchy.

Conventions (those of the common exporters): rotations are in degrees and compose in the order
the channels list them (``Zrotation Xrotation Yrotation`` is ``Rz @ Rx @ Ry``, each about the
joint's own, already rotated axes); a joint's position channels, when it has them, replace the
matching components of its offset; a joint's world rotation is its parent's times its own, its
world position its parent's plus the parent's world rotation applied to its local translation.

The reader is strict so that a damaged file is a one-line error naming the file and the line,
never a silently wrong skeleton: a truncated motion block, a frame with more or fewer values
than the hierarchy has channels, a value that is not a finite number (NaN, inf), an unknown
channel, unbalanced braces and a repeated joint name are each refused.

Why a reader of our own: of the BVH packages on PyPI, ``bvh`` (2017) and ``bvhtoolbox`` (2020,
built on it) are no longer kept, and ``bvhio`` (kept) pins exact versions of PyGLM and
spatial-transform, builds each frame's pose joint by joint in Python objects, ignores extra
values in a frame, fails on missing ones with an IndexError, and takes NaN without a word.
Reading the format strictly and its forward kinematics in NumPy, vectorised over frames, is
short.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rnnpb._reading import MAX_TEXT_FILE_BYTES, bounded_lines, open_regular_file
from rnnpb.errors import DataFileError

CHANNEL_NAMES = ("Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation")
MAX_BVH_LINE_CHARS = 1 << 20
"""Longest line read (1 Mi characters: one frame of a skeleton of thousands of channels)."""
MAX_JOINTS = 1000
MAX_FRAMES = 1_000_000


@dataclass(frozen=True)
class Joint:
    """One joint of a BVH skeleton.

    Attributes
    ----------
    name : str
    parent : int
        Index of the parent joint, -1 for the root.
    offset : array, shape (3,)
        Rest translation from the parent, in the file's units.
    channels : tuple of str
        The channels the motion drives, in order (names from :data:`CHANNEL_NAMES`).
    first_channel : int
        Column of the first of them in a motion line.
    """

    name: str
    parent: int
    offset: np.ndarray
    channels: tuple[str, ...]
    first_channel: int


@dataclass(frozen=True)
class Bvh:
    """A BVH file's skeleton and motion.

    Attributes
    ----------
    path : Path
    joints : tuple of Joint
        Parents before children (file order).
    frame_time : float
        Seconds per frame.
    motion : array, shape (n_frames, n_channels)
        Channel values per frame (degrees for rotations, file units for positions).
    """

    path: Path
    joints: tuple[Joint, ...]
    frame_time: float
    motion: np.ndarray

    @property
    def n_frames(self) -> int:
        return int(self.motion.shape[0])

    @property
    def duration(self) -> float:
        """Seconds from the first frame to the last."""
        return self.frame_time * max(self.n_frames - 1, 0)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(joint.name for joint in self.joints)

    def index(self, name: str) -> int:
        """The index of the joint called ``name``; :class:`DataFileError` if none is."""
        try:
            return self.names.index(name)
        except ValueError:
            raise DataFileError(f"{self.path}: no joint called {name!r}") from None

    def ancestors(self, index: int) -> list[int]:
        """The joint's parent, grandparent, … up to the root."""
        out = []
        while (index := self.joints[index].parent) >= 0:
            out.append(index)
        return out

    def world_positions(self) -> np.ndarray:
        """Every joint's position in the file's world frame, shape (n_frames, n_joints, 3)."""
        n = self.n_frames
        rotations = np.empty((len(self.joints), n, 3, 3))
        positions = np.empty((len(self.joints), n, 3))
        for j, joint in enumerate(self.joints):
            translation = np.broadcast_to(joint.offset, (n, 3)).copy()
            local = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
            for k, channel in enumerate(joint.channels):
                values = self.motion[:, joint.first_channel + k]
                axis = "XYZ".index(channel[0])
                if channel.endswith("position"):
                    translation[:, axis] = values
                else:
                    local = local @ _axis_rotation(axis, np.radians(values))
            if joint.parent < 0:
                rotations[j], positions[j] = local, translation
            else:
                parent_rotation = rotations[joint.parent]
                rotations[j] = parent_rotation @ local
                positions[j] = positions[joint.parent] + np.einsum(
                    "nij,nj->ni", parent_rotation, translation
                )
        return positions.transpose(1, 0, 2)


def _axis_rotation(axis: int, angle: np.ndarray) -> np.ndarray:
    """Rotations about one coordinate axis by ``angle`` (n,) radians, shape (n, 3, 3)."""
    c, s = np.cos(angle), np.sin(angle)
    out = np.zeros((len(angle), 3, 3))
    i, k = [(1, 2), (2, 0), (0, 1)][axis]
    out[:, axis, axis] = 1.0
    out[:, i, i] = out[:, k, k] = c
    out[:, i, k] = -s
    out[:, k, i] = s
    return out


class _Lines:
    """A BVH file's non-blank lines as (number, tokens), with the file for messages."""

    def __init__(self, path: Path, lines) -> None:
        self.path = path
        self._lines = lines
        self.number = 0

    def error(self, problem: str, number: int | None = None) -> DataFileError:
        return DataFileError(
            f"{self.path}, line {self.number if number is None else number}: {problem}"
        )

    def next(self, expected: str) -> list[str]:
        for line in self._lines:
            self.number += 1
            tokens = line.split()
            if tokens:
                return tokens
        raise DataFileError(
            f"{self.path}, line {self.number + 1}: file ends where {expected} was expected"
        )

    def rest(self):
        for line in self._lines:
            self.number += 1
            yield line


def read_bvh(path: str | Path) -> Bvh:
    """Read a BVH file; any problem raises :class:`DataFileError` naming the file and line."""
    path = Path(path)
    with open_regular_file(
        path, DataFileError, "a BVH file", MAX_TEXT_FILE_BYTES, newline=""
    ) as handle:
        try:
            lines = _Lines(
                path, bounded_lines(handle, path, DataFileError, max_chars=MAX_BVH_LINE_CHARS)
            )
            return _parse(path, lines)
        except UnicodeDecodeError:
            raise DataFileError(f"{path}: not a text file (expected a BVH file)") from None


def _parse(path: Path, lines: _Lines) -> Bvh:
    tokens = lines.next("HIERARCHY")
    if tokens != ["HIERARCHY"]:
        raise lines.error("expected HIERARCHY (is this a BVH file?)")
    tokens = lines.next("ROOT")
    if len(tokens) != 2 or tokens[0] != "ROOT":
        raise lines.error("expected ROOT and the root joint's name")
    joints: list[Joint] = []
    _joint(lines, tokens[1], -1, joints)
    n_channels = sum(len(j.channels) for j in joints)
    tokens = lines.next("MOTION")
    if tokens == ["ROOT"] or (tokens and tokens[0] == "ROOT"):
        raise lines.error("a second ROOT: rnnpb reads BVH files of one skeleton")
    if tokens != ["MOTION"]:
        raise lines.error(f"expected MOTION after the hierarchy, got {' '.join(tokens)[:40]!r}")
    tokens = lines.next("Frames:")
    if len(tokens) != 2 or tokens[0] != "Frames:" or not tokens[1].isdigit():
        raise lines.error("expected 'Frames: N'")
    n_frames = int(tokens[1])
    if not 1 <= n_frames <= MAX_FRAMES:
        raise lines.error(f"Frames: {n_frames} is not from 1 to {MAX_FRAMES:,}")
    tokens = lines.next("Frame Time:")
    if len(tokens) != 3 or tokens[:2] != ["Frame", "Time:"]:
        raise lines.error("expected 'Frame Time: SECONDS'")
    frame_time = _number(lines, tokens[2], "the frame time")
    if not 1e-4 <= frame_time <= 10.0:
        raise lines.error(f"Frame Time {frame_time} s is not from 0.0001 to 10 s")
    motion = np.empty((n_frames, n_channels))
    frame = 0
    for line in lines.rest():
        values = line.split()
        if not values:
            continue
        if frame == n_frames:
            raise lines.error(f"more frames than 'Frames: {n_frames}' says")
        if len(values) != n_channels:
            raise lines.error(
                f"frame {frame + 1} has {len(values)} values; the hierarchy has "
                f"{n_channels} channels"
            )
        try:
            row = np.array(values, dtype=np.float64)
        except ValueError:
            bad = next(v for v in values if not _is_float(v))
            raise lines.error(f"frame {frame + 1}: {bad[:20]!r} is not a number") from None
        if not np.isfinite(row).all():
            bad = values[int(np.argmin(np.isfinite(row)))]
            raise lines.error(f"frame {frame + 1}: {bad[:20]!r} is not a finite number")
        motion[frame] = row
        frame += 1
    if frame < n_frames:
        raise lines.error(
            f"the motion block ends after {frame} of the {n_frames} frames 'Frames:' "
            "announces (file truncated?)",
            lines.number + 1,
        )
    return Bvh(path, tuple(joints), frame_time, motion)


def _joint(lines: _Lines, name: str, parent: int, joints: list[Joint]) -> None:
    if name in (j.name for j in joints):
        raise lines.error(f"a second joint called {name!r}")
    if len(joints) >= MAX_JOINTS:
        raise lines.error(f"more than {MAX_JOINTS} joints")
    if lines.next("{") != ["{"]:
        raise lines.error(f"expected '{{' opening joint {name!r}")
    offset = _offset(lines)
    tokens = lines.next("CHANNELS")
    if tokens[0] != "CHANNELS" or len(tokens) < 2 or not tokens[1].isdigit():
        raise lines.error(f"expected 'CHANNELS N …' for joint {name!r}")
    count, channels = int(tokens[1]), tuple(tokens[2:])
    if count != len(channels):
        raise lines.error(f"joint {name!r}: CHANNELS {count} lists {len(channels)} channels")
    unknown = [c for c in channels if c not in CHANNEL_NAMES]
    if unknown:
        raise lines.error(f"joint {name!r}: unknown channel {unknown[0]!r}")
    if len(set(channels)) != len(channels):
        raise lines.error(f"joint {name!r}: a channel is listed twice")
    first = sum(len(j.channels) for j in joints)
    index = len(joints)
    joints.append(Joint(name, parent, offset, channels, first))
    while True:
        tokens = lines.next("JOINT, End Site or '}'")
        if tokens == ["}"]:
            return
        if tokens[0] == "JOINT" and len(tokens) == 2:
            _joint(lines, tokens[1], index, joints)
        elif tokens == ["End", "Site"]:
            if lines.next("{") != ["{"]:
                raise lines.error("expected '{' opening an End Site")
            _offset(lines)
            if lines.next("}") != ["}"]:
                raise lines.error("expected '}' closing an End Site")
        else:
            raise lines.error(
                f"expected JOINT NAME, End Site or '}}' in joint {name!r}, "
                f"got {' '.join(tokens)[:40]!r}"
            )


def _offset(lines: _Lines) -> np.ndarray:
    tokens = lines.next("OFFSET")
    if tokens[0] != "OFFSET" or len(tokens) != 4:
        raise lines.error("expected 'OFFSET X Y Z'")
    return np.array([_number(lines, t, "an offset") for t in tokens[1:]])


def _number(lines: _Lines, text: str, what: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise lines.error(f"{what} {text[:20]!r} is not a number") from None
    if not math.isfinite(value):
        raise lines.error(f"{what} {text[:20]!r} is not a finite number")
    return value


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True
