"""How the network's eight joints reach a robot's own joints: names, signs, offsets, limits.

The network speaks of eight joints (``lshp lshr lshy lelp rshp rshr rshy relp``, radians, the
simulated humanoid's zero pose and directions). A real robot names its joints its own way,
turns some of them the other way round and has its zero elsewhere. A robot map says, per
network joint::

    robot angle = sign * network angle + offset        (radians)

and the robot's own limits on the robot angle. It is a TOML file (``--robot-map FILE``)::

    # the eight network joints, each a table; every key is optional
    [joints.lshp]
    name = "left_shoulder_pitch_joint"   # the robot's joint name (default: lshp)
    sign = -1                            # 1 or -1 (default 1)
    offset = 0.5                         # radians added after the sign (default 0)
    limits = [-2.0, 1.0]                 # radians, the robot's own (default: the humanoid's,
                                         # mapped by sign and offset)

Without a file the map is the simulated humanoid's: its names, sign 1, offset 0, its limits.
Any error names the file and the key, on one line.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.robot._kinematics import JOINT_LIMITS
from rnnpb.vectors import MOTOR_NAMES, MOTOR_SIZE

_JOINT_KEYS = ("name", "sign", "offset", "limits")


@dataclass(frozen=True)
class RobotMap:
    """The robot's joints for the network's eight, in ``MOTOR_NAMES`` order.

    Attributes
    ----------
    names : tuple of str, length 8
        The robot's joint names.
    sign : array, shape (8,)
        1 or -1 per joint.
    offset : array, shape (8,)
        Radians added after the sign.
    limits : array, shape (8, 2)
        (lower, upper) radians of each robot joint, in the robot's own angles.
    origin : str
        Where the map came from (a file, or ``"the simulated humanoid"``).
    """

    names: tuple[str, ...]
    sign: np.ndarray
    offset: np.ndarray
    limits: np.ndarray
    origin: str = "the simulated humanoid"

    def __post_init__(self) -> None:
        where = self.origin
        if len(self.names) != MOTOR_SIZE:
            raise ConfigError(f"{where}: a robot map names {MOTOR_SIZE} joints")
        if len(set(self.names)) != MOTOR_SIZE:
            raise ConfigError(f"{where}: two joints have the same name")
        sign = np.asarray(self.sign, dtype=np.float64).reshape(MOTOR_SIZE)
        offset = np.asarray(self.offset, dtype=np.float64).reshape(MOTOR_SIZE)
        limits = np.asarray(self.limits, dtype=np.float64).reshape(MOTOR_SIZE, 2)
        for array in (sign, offset, limits):
            array.setflags(write=False)
        object.__setattr__(self, "sign", sign)
        object.__setattr__(self, "offset", offset)
        object.__setattr__(self, "limits", limits)

    @classmethod
    def humanoid(cls) -> RobotMap:
        """The simulated humanoid's own map: its names, sign 1, offset 0, its limits."""
        return cls(MOTOR_NAMES, np.ones(MOTOR_SIZE), np.zeros(MOTOR_SIZE), JOINT_LIMITS)

    @classmethod
    def load(cls, path: str | Path) -> RobotMap:
        """Read a robot map file (see the module doc); :class:`ConfigError` names the file and
        the key of any problem."""
        path = Path(path)
        try:
            table = tomllib.loads(path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise ConfigError(f"{path}: no such robot map file") from None
        except (OSError, UnicodeDecodeError) as error:
            raise ConfigError(f"{path}: cannot read the robot map: {error}") from None
        except tomllib.TOMLDecodeError as error:
            raise ConfigError(f"{path}: not a TOML file: {error}") from None
        return cls.from_table(table, str(path))

    @classmethod
    def from_table(cls, table: dict[str, Any], origin: str) -> RobotMap:
        unknown = sorted(set(table) - {"joints"})
        if unknown:
            raise ConfigError(f"{origin}: unknown key {unknown[0]!r} (a robot map has [joints.*])")
        joints = table.get("joints")
        if not isinstance(joints, dict):
            raise ConfigError(
                f"{origin}: joints: missing; a robot map has a [joints.NAME] table for each of "
                + ", ".join(MOTOR_NAMES)
            )
        extra = sorted(set(joints) - set(MOTOR_NAMES))
        if extra:
            raise ConfigError(
                f"{origin}: joints.{extra[0]}: not a network joint (one of "
                f"{', '.join(MOTOR_NAMES)})"
            )
        humanoid = cls.humanoid()
        names, sign, offset, limits = [], [], [], []
        for i, joint in enumerate(MOTOR_NAMES):
            key = f"joints.{joint}"
            entry = joints.get(joint)
            if not isinstance(entry, dict):
                raise ConfigError(f"{origin}: {key}: missing (a robot map maps all eight joints)")
            unknown = sorted(set(entry) - set(_JOINT_KEYS))
            if unknown:
                raise ConfigError(
                    f"{origin}: {key}.{unknown[0]}: unknown key (one of {', '.join(_JOINT_KEYS)})"
                )
            name = entry.get("name", joint)
            if not isinstance(name, str) or not name.strip():
                raise ConfigError(f"{origin}: {key}.name: must be a non-empty string")
            s = entry.get("sign", 1)
            if isinstance(s, bool) or s not in (1, -1):
                raise ConfigError(f"{origin}: {key}.sign: must be 1 or -1, got {s!r:.40}")
            o = _number(entry.get("offset", 0.0), origin, f"{key}.offset")
            if "limits" in entry:
                pair = entry["limits"]
                if not isinstance(pair, list) or len(pair) != 2:
                    raise ConfigError(f"{origin}: {key}.limits: must be [lower, upper] radians")
                lo = _number(pair[0], origin, f"{key}.limits")
                hi = _number(pair[1], origin, f"{key}.limits")
                if not lo < hi:
                    raise ConfigError(f"{origin}: {key}.limits: lower must be below upper")
            else:
                lo, hi = sorted(s * humanoid.limits[i] + o)
            names.append(name.strip())
            sign.append(float(s))
            offset.append(o)
            limits.append((lo, hi))
        duplicate = next((n for n in names if names.count(n) > 1), None)
        if duplicate is not None:
            raise ConfigError(f"{origin}: joints: the name {duplicate!r} is given twice")
        return cls(tuple(names), np.array(sign), np.array(offset), np.array(limits), origin)

    def to_robot(self, joints: np.ndarray) -> np.ndarray:
        """Network angles (8,) → the robot's angles (8,), not clipped."""
        return self.sign * np.asarray(joints, dtype=np.float64) + self.offset

    def to_network(self, robot_joints: np.ndarray) -> np.ndarray:
        """The robot's angles (8,) → network angles (8,)."""
        return (np.asarray(robot_joints, dtype=np.float64) - self.offset) * self.sign

    def clip(self, robot_joints: np.ndarray) -> np.ndarray:
        """The robot's angles (8,) clipped to its limits."""
        return np.clip(robot_joints, self.limits[:, 0], self.limits[:, 1])

    def describe(self) -> str:
        return f"robot map of {self.origin}: joints {', '.join(self.names)}"


def _number(value: Any, origin: str, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ConfigError(f"{origin}: {key}: must be a finite number of radians, got {value!r:.40}")
    return float(value)
