"""A robot's hands seen in the person's space: how two robots, or a robot and a person, see
each other (the paper's section 4.2).

What an agent shows its partner is its hands *in the person's space*: where a person's hands
would be, in the seeing robot's frame, for the robot's camera to see them as it saw its teachers
(``lhy lhz rhy rhz``, :meth:`rnnpb.robot.camera.RobotCamera.sensory_from_hands`).

The scale mapping between a robot's body and a person's. The robot imitates a person through
the mirror mapping (:class:`rnnpb.demonstrator.MirrorMapping`): each person's hand, relative to
the person's shoulder, reflected through the plane between them and scaled by
``s = (L1 + L2) / arm_reach`` (robot arm reach over a person's, 0.21 m / 0.62 m = 0.34),
placed at the robot's opposite-side shoulder. A robot facing a robot is seen through the
inverse of that mapping: its hands by forward kinematics
(:func:`rnnpb.robot.forward_kinematics`), relative to its shoulders, scaled by ``1 / s``,
reflected back and placed at a person's shoulders (:class:`rnnpb.demonstrator.UserBody`) — the
person the robot would be imitating (``view="mirrored"``, the default). So a robot moving a
learned pattern is seen moving that pattern. Physically, a robot facing another sees it turned
half a turn (``view="physical"``): left and right swap sides and the circles of patterns 3 and
4 turn the other way, which the robots never learned; "mirrored" is that view flipped left to
right, as in a mirror.
"""

from __future__ import annotations

import numpy as np

from rnnpb.demonstrator import UserBody
from rnnpb.errors import ConfigError
from rnnpb.model.generation import generate
from rnnpb.model.io import TrainedModel
from rnnpb.robot import FOREARM_LENGTH, SHOULDERS, UPPER_ARM_LENGTH, forward_kinematics
from rnnpb.robot.camera import RobotCamera

VIEWS = ("mirrored", "physical")
WARMUP = 48  # closed-loop steps generated before an initiative is played (4 cycles)
REFERENCE_STEPS = 240  # closed-loop steps (after the warm-up) a learned pattern is judged by
_REFLECT_X = np.array([-1.0, 1.0, 1.0])
_TURN = np.array([-1.0, -1.0, 1.0])  # half a turn about the vertical axis


def robot_to_person_scale(body: UserBody | None = None) -> float:
    """Metres of a person's hand movement per metre of the robot's: ``arm_reach / (L1 + L2)``."""
    body = body or UserBody()
    return body.arm_reach / (UPPER_ARM_LENGTH + FOREARM_LENGTH)


def person_hands(
    joints: np.ndarray, body: UserBody | None = None, view: str = "mirrored"
) -> np.ndarray:
    """A robot's joint angles (..., 8) → its hands in the person's space (..., 2, 3): where a
    person's hands would be (robot frame of the robot that sees it), [left, right]."""
    if view not in VIEWS:
        raise ConfigError(f"view must be one of {', '.join(VIEWS)}, got {view!r}")
    body = body or UserBody()
    hands, _ = forward_kinematics(joints)
    relative = (hands - SHOULDERS) * robot_to_person_scale(body)
    if view == "mirrored":
        # The inverse of MirrorMapping: the robot's right arm shows the person's left hand.
        return body.shoulders + relative[..., ::-1, :] * _REFLECT_X
    # Turned half a turn: the robot's left arm is on the seer's right, where a person's left
    # hand is.
    return body.shoulders + relative * _TURN


def pattern_references(
    model: TrainedModel,
    view: str = "mirrored",
    n_steps: int = REFERENCE_STEPS,
    body: UserBody | None = None,
    camera: RobotCamera | None = None,
) -> dict[str, np.ndarray]:
    """Each learned pattern as this robot's network plays it, seen as its partner sees it:
    the closed-loop generation from the pattern's learned PB and initial context, after the
    warm-up an initiative skips (:data:`WARMUP`), ``n_steps`` steps; name -> (n_steps, 4).

    The measures judge a robot's movement against these (and the pattern as taught): a
    paper-learned network's closed loop may play a learned pattern otherwise than the
    demonstrator did, or not repeat at all (docs/dyad.md), and it is still that pattern."""
    camera = camera or RobotCamera()
    out = {}
    for name in model.patterns:
        generated = generate(
            model,
            np.clip(model.pattern_pb[name], 0.0, 1.0),
            WARMUP + n_steps,
            initial_context=model.pattern_initial_context(name),
        )
        out[name] = camera.sensory_from_hands(
            person_hands(np.asarray(generated.motor[WARMUP:]), body, view)
        )
    return out
