"""Robot maps (names, signs, offsets, limits of a real robot's joints) and the robot-side
safeguards."""

from __future__ import annotations

import numpy as np
import pytest

from rnnpb.cli import main
from rnnpb.errors import ConfigError
from rnnpb.robot import JOINT_LIMITS, RobotMap, Safeguard, Watchdog
from rnnpb.vectors import MOTOR_NAMES


def _full_map(**override: str) -> str:
    tables = {name: f'[joints.{name}]\nname = "{name}_joint"\n' for name in MOTOR_NAMES}
    tables.update(override)
    return "\n".join(tables.values())


def test_a_map_turns_network_angles_into_the_robots_and_back(tmp_path):
    path = tmp_path / "arm.toml"
    path.write_text(
        _full_map(lshp='[joints.lshp]\nname = "shoulder"\nsign = -1\noffset = 0.5\n').replace(
            "[joints.relp]\n", "[joints.relp]\nlimits = [0.2, 1.0]\n"
        )
    )
    robot_map = RobotMap.load(path)
    assert robot_map.names[0] == "shoulder" and robot_map.names[1] == "lshr_joint"
    joints = np.linspace(0.1, 0.8, 8)
    robot = robot_map.to_robot(joints)
    assert robot[0] == pytest.approx(0.5 - 0.1)
    np.testing.assert_allclose(robot_map.to_network(robot), joints)
    # Without limits, a joint keeps the humanoid's, turned by its sign and offset.
    np.testing.assert_allclose(robot_map.limits[0], sorted(0.5 - JOINT_LIMITS[0]))
    np.testing.assert_array_equal(robot_map.limits[7], [0.2, 1.0])
    assert robot_map.clip(np.full(8, 5.0))[7] == 1.0


def test_the_humanoids_map_is_the_identity():
    robot_map = RobotMap.humanoid()
    assert robot_map.names == MOTOR_NAMES
    joints = np.linspace(-0.2, 0.9, 8)
    np.testing.assert_array_equal(robot_map.to_network(robot_map.to_robot(joints)), joints)
    np.testing.assert_array_equal(robot_map.limits, JOINT_LIMITS)


@pytest.mark.parametrize(
    ("text", "key"),
    [
        ("this is = = not toml", "not a TOML file"),
        ("[arms]\n", "unknown key 'arms'"),
        (_full_map(relp=""), "joints.relp: missing"),
        (_full_map() + "[joints.neck]\n", "joints.neck: not a network joint"),
        (_full_map(lshp="[joints.lshp]\nsign = 2\n"), "joints.lshp.sign: must be 1 or -1"),
        (_full_map(lshp='[joints.lshp]\noffset = "x"\n'), "joints.lshp.offset: must be a finite"),
        (_full_map(lshp="[joints.lshp]\nlimits = [1.0]\n"), "joints.lshp.limits: must be"),
        (_full_map(lshp="[joints.lshp]\nlimits = [1.0, 0.5]\n"), "joints.lshp.limits: lower"),
        (_full_map(lshp="[joints.lshp]\nspeed = 3\n"), "joints.lshp.speed: unknown key"),
        (_full_map(lshp='[joints.lshp]\nname = "relp_joint"\n'), "'relp_joint' is given twice"),
    ],
)
def test_a_bad_map_is_one_line_naming_the_file_and_the_key(tmp_path, text, key):
    path = tmp_path / "arm.toml"
    path.write_text(text)
    with pytest.raises(ConfigError) as error:
        RobotMap.load(path)
    message = str(error.value)
    assert message.startswith(f"{path}: ") and key in message and "\n" not in message


def test_the_command_line_says_a_bad_map_in_one_line(tmp_path, capsys):
    path = tmp_path / "arm.toml"
    path.write_text(_full_map(rshy="[joints.rshy]\nsign = 0\n"))
    assert main(["robot", "serve", "--sim", "kinematic", "--robot-map", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"rnnpb: error: {path}: joints.rshy.sign: must be 1 or -1, got 0"
    assert main(["robot", "serve", "--robot-map", str(tmp_path / "none.toml")]) == 2
    assert "none.toml: no such robot map file" in capsys.readouterr().err


def test_the_safeguard_clips_then_slows_and_counts():
    guard = Safeguard(JOINT_LIMITS, dt=0.1, max_step=0.5)
    guard.reset(np.zeros(8))
    target = np.full(8, 0.3)
    np.testing.assert_array_equal(guard.apply(target), target)  # within reach: exact
    assert (guard.clipped, guard.slowed) == (0, 0)
    far = np.full(8, 10.0)
    np.testing.assert_allclose(guard.apply(far), np.minimum(0.8, JOINT_LIMITS[:, 1]))
    assert (guard.clipped, guard.slowed) == (1, 1)


def test_the_watchdog_expires_after_its_steps():
    dog = Watchdog(dt=0.4, steps=2)
    assert not dog.expired(100.0)  # nothing to hold before the first command
    dog.fed(100.0)
    assert not dog.expired(100.8) and dog.expired(100.81)
