"""Hands relative to the person's body: any naming, unit, up axis, heading and size give the
standard user's hands, so the robot's joint angles are the same."""

from __future__ import annotations

import numpy as np
import pytest

from rnnpb.demonstrator import MirrorMapping
from rnnpb.errors import DataFileError
from rnnpb.mocap import body_hands, read_bvh

from .bvh_files import demonstrator_hands, write_bvh

FPS = 30
TIMES = np.arange(45) / FPS


@pytest.fixture(scope="module")
def movement():
    return demonstrator_hands("3", TIMES, 1.5)


@pytest.mark.parametrize(
    "variant",
    [
        {},
        {"naming": "underscore", "unit": "m"},
        {"naming": "lower", "unit": "mm", "up": "z"},
        {"up": "z", "heading_deg": 35.0, "drift": 0.3},
        {"unit": "in", "heading_deg": 180.0},
    ],
    ids=["cmu-cm-y", "underscore-m", "lower-mm-z", "z-up-turned-walking", "inches-facing-back"],
)
def test_another_naming_unit_or_up_axis_gives_the_same_hands(tmp_path, movement, variant):
    path = write_bvh(tmp_path / "take.bvh", movement, 1 / FPS, **variant)
    hands, scale = body_hands(read_bvh(path))
    np.testing.assert_allclose(hands, movement, atol=1e-5)
    assert scale.units == variant.get("unit", "cm") and scale.units_detected
    assert scale.up_axis == variant.get("up", "y") and scale.up_detected
    assert scale.arm_length_m == pytest.approx(0.62, abs=1e-4)
    assert scale.shoulder_width_m == pytest.approx(0.38, abs=1e-4)


def test_a_child_and_a_tall_adult_reach_the_same_robot_posture(tmp_path, movement):
    mapping = MirrorMapping()
    joints, scales = [], []
    for size, unit in ((0.55, "cm"), (1.35, "m")):
        path = write_bvh(tmp_path / f"size{size}.bvh", movement, 1 / FPS, size=size, unit=unit)
        hands, scale = body_hands(read_bvh(path))
        np.testing.assert_allclose(hands, movement, atol=1e-5)
        joints.append(mapping.motor_from_hands(hands))
        scales.append(scale)
    np.testing.assert_allclose(joints[0], joints[1], atol=1e-6)
    assert scales[0].arm_length_m == pytest.approx(0.55 * 0.62, abs=1e-4)
    assert scales[1].arm_length_m == pytest.approx(1.35 * 0.62, abs=1e-4)
    assert scales[0].scale == pytest.approx(1 / 0.55, rel=1e-4)


def test_given_units_and_up_axis_are_used(tmp_path, movement):
    path = write_bvh(tmp_path / "take.bvh", movement, 1 / FPS, unit="m", up="z")
    bvh = read_bvh(path)
    hands, scale = body_hands(bvh, units="cm", up_axis="z")
    # the hands do not depend on the unit (the body's own size scales them) ...
    np.testing.assert_allclose(hands, movement, atol=1e-5)
    # ... but the measures recorded with the data do
    assert scale.arm_length_m == pytest.approx(0.0062, abs=1e-6)
    assert not scale.units_detected and not scale.up_detected
    wrong, _ = body_hands(bvh, up_axis="y")
    assert np.abs(wrong - movement).max() > 0.1


def test_a_skeleton_without_named_hands_says_how_to_name_them(tmp_path, movement):
    path = write_bvh(tmp_path / "take.bvh", movement, 1 / FPS)
    text = path.read_text().replace("LeftHand", "Paw_A").replace("RightHand", "Paw_B")
    path.write_text(text)
    bvh = read_bvh(path)
    with pytest.raises(DataFileError, match="left hand .* --hands LEFT,RIGHT"):
        body_hands(bvh)
    hands, _ = body_hands(bvh, hands=("Paw_A", "Paw_B"))
    np.testing.assert_allclose(hands, movement, atol=1e-5)
