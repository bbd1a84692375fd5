"""The independent judges: collisions by MuJoCo's own contacts, speed against the servo, limits
and reach by MuJoCo's kinematics; and how far they agree with the safety checker they judge."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from rnnpb.analysis.judges import (
    EXCLUDED_BODY_PAIRS,
    PASS_THROUGH_DEPTH,
    CollisionJudge,
    Kinematics,
    judge_limits,
    judge_model_xml,
    judge_reach,
    judge_speed,
    servo_step_limit,
)
from rnnpb.errors import ConfigError
from rnnpb.robot import JOINT_LIMITS

# Arms a little forward and out, elbows bent: clear of the body (the retargeting's start).
CLEAR = np.array([0.2, 0.35, 0.0, 0.6, 0.2, 0.35, 0.0, 0.6])
# The left arm hanging straight and rolled across the body (roll -0.25 rad, the limit): the
# upper arm, elbow and forearm inside the chest, the hand inside the hip.
THROUGH_TORSO = np.array([0.0, -0.25, 0.0, 0.0, 0.2, 0.35, 0.0, 0.6])


@pytest.fixture(scope="module")
def judge():
    return CollisionJudge()


@pytest.mark.parametrize(
    "rest",
    [
        np.zeros(8),  # every joint 0: the arms hanging
        np.array([0.0, 0.0, 0.0, 1.4] * 2),  # the MuJoCo robot's rest: elbows at 1.4 rad
        CLEAR,
    ],
)
def test_the_rest_postures_do_not_collide(judge, rest):
    assert judge.contacts(rest) == []
    assert judge.judge(np.array([rest, rest])).colliding == ()


def test_what_touches_at_rest_is_within_the_clearance_or_excluded(judge):
    """The decision the exclusions rest on: at every joint 0 the upper arm lies 2 mm into the
    chest's side and the hanging hand 6 mm into the leg (within the clearance, so counted
    when deeper), while each shoulder ball sits 8 mm in the chest at every posture (its
    housing: excluded)."""
    touching = {(c.part, c.other): c.depth for c in judge.touching(np.zeros(8))}
    assert touching[("lupper_arm_geom", "chest")] == pytest.approx(0.002, abs=1e-6)
    assert touching[("lhand_geom", "left_leg")] == pytest.approx(0.006, abs=1e-6)
    assert max(touching.values()) < PASS_THROUGH_DEPTH
    assert not any("shoulder_geom" in part + other for part, other in touching)
    # Without the exclusion, the shoulder ball is 8 mm in the chest whatever the joints.
    root = ET.fromstring(judge_model_xml())
    contact = root.find("contact")
    assert contact is not None
    for element in list(contact):
        contact.remove(element)
    unexcluded = _depths(ET.tostring(root, encoding="unicode"))
    rng = np.random.default_rng(3)
    for joints in rng.uniform(JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1], size=(20, 8)):
        depths = unexcluded(joints)
        assert depths[("lshoulder_geom", "chest")] == pytest.approx(0.008, abs=1e-9)
        assert depths[("rshoulder_geom", "chest")] == pytest.approx(0.008, abs=1e-9)
    assert {frozenset(pair) for pair in EXCLUDED_BODY_PAIRS} == {
        frozenset(("torso", "left_shoulder_roll")),
        frozenset(("torso", "right_shoulder_roll")),
    }


def _depths(xml: str):
    from rnnpb.analysis.judges import _mujoco
    from rnnpb.vectors import MOTOR_NAMES

    mj = _mujoco()
    model = mj.MjModel.from_xml_string(xml)
    data = mj.MjData(model)
    qpos = [model.jnt_qposadr[model.joint(name).id] for name in MOTOR_NAMES]

    def depths(joints):
        data.qpos[qpos] = joints
        mj.mj_forward(model, data)
        out = {}
        for i in range(data.ncon):
            c = data.contact[i]
            out[(model.geom(int(c.geom1)).name, model.geom(int(c.geom2)).name)] = -c.dist
        return out

    return depths


def test_an_arm_through_the_torso_is_counted(judge):
    hits = {(c.part, c.other) for c in judge.contacts(THROUGH_TORSO)}
    assert ("lupper_arm_geom", "chest") in hits and ("lforearm_geom", "chest") in hits
    verdict = judge.judge(np.array([CLEAR, THROUGH_TORSO, CLEAR]))
    # The step into the torso collides at its posture, the step out of it on the way.
    assert verdict.colliding == (1, 2) and verdict.count == 2
    assert any(c.where == 1.0 for c in verdict.contacts[1])
    assert all(c.where < 1.0 for c in verdict.contacts[2])


def test_a_step_whose_way_passes_through_the_body_is_counted(judge):
    """Both postures clear, the straight way between them through the hip and the chest."""
    start = np.array([-0.9, 0.02, -0.65, 0.81, *CLEAR[4:]])
    end = np.array([0.75, 0.32, -0.57, 1.11, *CLEAR[4:]])
    assert not judge.collides(start) and not judge.collides(end)
    verdict = judge.judge(np.array([end]), previous=start)
    assert verdict.colliding == (0,)
    assert {c.other for c in verdict.contacts[0]} >= {"pelvis", "chest"}
    assert CollisionJudge(path_points=0).judge(np.array([end]), previous=start).count == 0


def test_a_step_faster_than_the_servo_is_counted():
    # The AX-12A's 59 rev/min at dt 0.4 s: 2.47 rad a step.
    limit = servo_step_limit(0.4)
    assert limit == pytest.approx(59 * 2 * math.pi / 60 * 0.4)
    fast = CLEAR.copy()
    fast[0] += limit + 0.01  # shoulder pitch a hundredth of a radian past the servo
    almost = fast.copy()
    almost[4] += limit - 0.01  # the other shoulder a hundredth short of it
    verdict = judge_speed(np.array([CLEAR, fast, fast, almost]), dt=0.4)
    assert verdict.too_fast == (1,) and verdict.count == 1
    assert verdict.largest_change == pytest.approx([0.0, limit + 0.01, 0.0, limit - 0.01])
    # From a previous posture the first step is judged too.
    assert judge_speed(np.array([fast]), dt=0.4, previous=CLEAR).too_fast == (0,)
    assert judge_speed(np.array([fast]), dt=0.8, previous=CLEAR).count == 0


def test_the_speed_limit_and_the_safety_check_s_agree():
    """Two readings of one datasheet: the judge's and the safety module's step limit."""
    from rnnpb.safety import SafetyLimits

    for dt in (0.1, 0.4):
        assert servo_step_limit(dt) == pytest.approx(SafetyLimits(dt=dt).step_limit)


def test_joints_outside_the_mjcf_s_ranges_are_counted():
    kinematics = Kinematics()
    assert np.allclose(kinematics.joint_ranges, JOINT_LIMITS)
    outside = CLEAR.copy()
    outside[3] = 2.5  # elbow past 2.4
    assert judge_limits(np.array([CLEAR, outside]), kinematics).outside == (1,)


def test_reach_by_mujoco_s_kinematics_matches_the_robot_s_own():
    from rnnpb.robot import forward_kinematics

    rng = np.random.default_rng(0)
    postures = rng.uniform(JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1], size=(200, 8))
    kinematics = Kinematics()
    hands, _ = forward_kinematics(postures)
    verdict = judge_reach(postures, hands, kinematics=kinematics)
    assert verdict.count == 0 and verdict.mean_distance is not None
    assert verdict.mean_distance < 1e-9
    assert np.allclose(verdict.hands, hands, atol=1e-9)
    away = hands.copy()
    away[5, 1, 2] += 0.02  # the right hand asked 2 cm higher at step 5
    assert judge_reach(postures, away, kinematics=kinematics).beyond == (5,)
    with pytest.raises(ConfigError, match="requested hands must have shape"):
        judge_reach(postures, hands[:, 0])


def test_the_judge_and_the_safety_checker_agree_on_random_postures(judge):
    """On 400 postures drawn uniformly within the joint limits (seed 2026) the two agree on
    94.75 % (379); every disagreement is the judge alone finding an upper arm 8-19 mm inside
    the chest, with the shoulder rolled across the body: the checker tests the upper arm
    against the head and the other arm only (robot/_collision.py). Nothing the checker finds
    is missed by the judge."""
    from rnnpb.robot import SelfCollision

    checker = SelfCollision()
    rng = np.random.default_rng(2026)
    postures = rng.uniform(JOINT_LIMITS[:, 0], JOINT_LIMITS[:, 1], size=(400, 8))
    agree, only_judge = 0, []
    for joints in postures:
        ours, theirs = judge.collides(joints), checker.collides(joints)
        agree += ours == theirs
        assert not (theirs and not ours), f"the checker alone collides at {joints}"
        if ours and not theirs:
            only_judge.append({(c.part, c.other) for c in judge.contacts(joints)})
    rate = agree / len(postures)
    assert rate >= 0.93, f"agreement {rate:.2%} (94.75 % when measured)"
    for pairs in only_judge:
        assert pairs <= {("lupper_arm_geom", "chest"), ("rupper_arm_geom", "chest")}, pairs


def test_the_demonstrator_s_learning_data_passes_the_judges(judge):
    """The contract "learned data never holds a colliding step", judged independently: the
    four patterns' demonstrations (8 sequences, 400 steps) have no colliding, too fast or
    out-of-range step."""
    from rnnpb.demonstrator import learning_set

    kinematics = Kinematics()
    for sequence in learning_set("full"):
        motor = np.asarray(sequence.motor)
        assert judge.judge(motor).count == 0
        assert judge_speed(motor, dt=0.4).count == 0
        assert judge_limits(motor, kinematics).count == 0


def test_a_malformed_path_is_one_clear_error(judge):
    with pytest.raises(ConfigError, match=r"motor must have shape \(T, 8\)"):
        judge.judge(np.zeros((3, 7)))
    with pytest.raises(ConfigError, match="must be finite"):
        judge_speed(np.full((2, 8), np.nan), dt=0.4)
