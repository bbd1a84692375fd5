"""MuJoCo's OpenGL is chosen when MuJoCo is first needed: the user's choice, else EGL, else
OSMesa, else a message that says what to install."""

import pytest

from rnnpb.errors import ConfigError
from rnnpb.robot import choose_gl


def test_the_users_choice_stands():
    env = {"MUJOCO_GL": "osmesa"}
    assert choose_gl(env, loadable=lambda library: True) == "osmesa"
    assert env == {"MUJOCO_GL": "osmesa"}


def test_egl_first_then_osmesa():
    env = {}
    assert choose_gl(env, loadable=lambda library: True) == "egl"
    assert env["MUJOCO_GL"] == "egl"
    env = {"MUJOCO_GL": ""}
    assert choose_gl(env, loadable=lambda library: library == "OSMesa") == "osmesa"
    assert env["MUJOCO_GL"] == "osmesa"


def test_neither_installed_says_what_to_do():
    env = {}
    with pytest.raises(ConfigError, match="neither EGL .* nor OSMesa.*set MUJOCO_GL"):
        choose_gl(env, loadable=lambda library: False)
    assert "MUJOCO_GL" not in env
