"""The humanoid in MuJoCo: the model (``humanoid.xml`` + the head camera) and a position
controlled :class:`MujocoRobot` behind the :class:`~rnnpb.robot.Robot` interface.

MuJoCo itself is imported when a model is first loaded (:mod:`rnnpb.robot._gl`), not here.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from importlib import resources
from typing import TYPE_CHECKING

import numpy as np

from rnnpb.errors import ConfigError
from rnnpb.robot._gl import import_mujoco
from rnnpb.robot._interface import Robot, as_joint_vector
from rnnpb.robot._kinematics import clip_to_limits
from rnnpb.robot.camera import RobotCamera
from rnnpb.vectors import MOTOR_NAMES

if TYPE_CHECKING:
    import mujoco

ROBOT_EYE = "robot_eye"
"""Name of the head camera in the model; its pose and field of view come from RobotCamera."""
USER_HAND_BODIES = ("user_left_hand", "user_right_hand")
"""Mocap bodies standing for the user's hands (left, right)."""


def model_xml(camera: RobotCamera | None = None) -> str:
    """The MJCF text of the humanoid with the head camera placed from ``camera``."""
    camera = camera or RobotCamera()
    text = resources.files("rnnpb.robot").joinpath("humanoid.xml").read_text(encoding="utf-8")
    root = ET.fromstring(text)
    head = root.find(".//body[@name='head']")
    if head is None or head.get("pos", "0 0 0").split() != ["0", "0", "0"]:
        raise ConfigError(
            "humanoid.xml: the head body must exist and sit at the robot-frame "
            "origin, so that the camera attributes are robot-frame coordinates"
        )
    ET.SubElement(head, "camera", {"name": ROBOT_EYE, **camera.mjcf_attributes()})
    return ET.tostring(root, encoding="unicode")


def load_model(camera: RobotCamera | None = None) -> mujoco.MjModel:
    """The compiled MuJoCo model of the humanoid (render buffers sized for ``camera``)."""
    camera = camera or RobotCamera()
    model = import_mujoco().MjModel.from_xml_string(model_xml(camera))
    model.vis.global_.offwidth = max(model.vis.global_.offwidth, camera.width)
    model.vis.global_.offheight = max(model.vis.global_.offheight, camera.height)
    return model


def joint_addresses(model: mujoco.MjModel) -> np.ndarray:
    """qpos addresses of the eight arm joints in MOTOR_NAMES order."""
    return np.array([model.jnt_qposadr[model.joint(name).id] for name in MOTOR_NAMES])


def set_pose(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    joints: np.ndarray,
    user_hands: np.ndarray | None = None,
) -> None:
    """Put the arms at ``joints`` (8,) radians and the user's hand balls at ``user_hands``
    (2, 3) (or keep them hidden), then update the kinematics (no physics)."""
    data.qpos[joint_addresses(model)] = clip_to_limits(joints)
    data.qvel[:] = 0.0
    set_user_hands(model, data, user_hands)
    import_mujoco().mj_forward(model, data)


def set_user_hands(
    model: mujoco.MjModel, data: mujoco.MjData, user_hands: np.ndarray | None
) -> None:
    """Place the user's hand balls (2, 3) in the robot frame; None hides them under the floor."""
    for i, name in enumerate(USER_HAND_BODIES):
        mocap = model.body(name).mocapid[0]
        if user_hands is None:
            data.mocap_pos[mocap] = (0.7, 0.2 * (2 * i - 1), -1.0)
        else:
            data.mocap_pos[mocap] = np.asarray(user_hands, dtype=np.float64)[i]


class MujocoRobot(Robot):
    """The humanoid simulated in MuJoCo, position controlled.

    Each :meth:`send` runs one network step of ``dt`` seconds: ``n_substeps`` physics steps
    (``dt / n_substeps`` must equal the model's timestep, 2 ms, unless ``timestep`` is given).
    The actuator set points move from the previous target to the new one over the first
    ``ramp_fraction`` of the step (a servo's trajectory generator; 0 jumps at once), then hold.

    Parameters
    ----------
    dt : float
        Seconds per network step (paper: 0.4 s).
    n_substeps : int or None
        Physics steps per network step; None: ``round(dt / 0.002)``.
    initial : array, shape (8,), optional
        Starting joint angles (radians); default: the coupled rest pose (all pitch and roll 0,
        elbow bent as the IK coupling gives at zero pitch).
    ramp_fraction : float
        Share of the step over which the set point ramps to the new target.
    camera : RobotCamera, optional
        The head camera model placed in the scene.
    """

    def __init__(
        self,
        dt: float = 0.4,
        n_substeps: int | None = None,
        initial: np.ndarray | None = None,
        ramp_fraction: float = 0.5,
        camera: RobotCamera | None = None,
    ) -> None:
        if dt <= 0:
            raise ConfigError(f"dt must be > 0, got {dt}")
        if n_substeps is None:
            n_substeps = max(1, round(dt / 0.002))
        if n_substeps < 1:
            raise ConfigError(f"n_substeps must be >= 1, got {n_substeps}")
        if not 0.0 <= ramp_fraction <= 1.0:
            raise ConfigError(f"ramp_fraction must be in [0, 1], got {ramp_fraction}")
        self.dt = float(dt)
        self.n_substeps = int(n_substeps)
        self.ramp_fraction = float(ramp_fraction)
        self.camera = camera or RobotCamera()
        if initial is None:
            from rnnpb.robot._kinematics import ELBOW_AT_ZERO_PITCH

            initial = np.array([0.0, 0.0, 0.0, ELBOW_AT_ZERO_PITCH] * 2)
        self._initial = clip_to_limits(as_joint_vector(initial, "initial"))
        self.model: mujoco.MjModel | None = None
        self.data: mujoco.MjData | None = None
        self._target = self._initial.copy()

    def connect(self) -> None:
        self.model = load_model(self.camera)
        self.model.opt.timestep = self.dt / self.n_substeps
        self._mujoco = import_mujoco()
        self.data = self._mujoco.MjData(self.model)
        self._qadr = joint_addresses(self.model)
        self._actuators = np.array([self.model.actuator(name).id for name in MOTOR_NAMES])
        set_pose(self.model, self.data, self._initial)
        self.data.ctrl[self._actuators] = self._initial
        self._target = self._initial.copy()

    def _require(self) -> tuple[mujoco.MjModel, mujoco.MjData]:
        if self.model is None or self.data is None:
            raise ConfigError("MujocoRobot: call connect() (or use it in a with block) first")
        return self.model, self.data

    @property
    def is_connected(self) -> bool:
        return self.data is not None

    def send(self, joint_targets: np.ndarray) -> np.ndarray:
        model, data = self._require()
        target = clip_to_limits(as_joint_vector(joint_targets))
        start = self._target
        ramp = max(1, round(self.ramp_fraction * self.n_substeps))
        for k in range(self.n_substeps):
            w = min(1.0, (k + 1) / ramp) if self.ramp_fraction > 0 else 1.0
            data.ctrl[self._actuators] = start + w * (target - start)
            self._mujoco.mj_step(model, data)
        self._target = target
        return target.copy()

    def observe(self) -> np.ndarray:
        _, data = self._require()
        return data.qpos[self._qadr].copy()

    def hand_positions(self) -> np.ndarray:
        """The simulated hands (left, right) in the robot frame, shape (2, 3)."""
        model, data = self._require()
        self._mujoco.mj_kinematics(model, data)  # after mj_step, xpos lags qpos by one substep
        return np.stack([data.site("left_hand").xpos, data.site("right_hand").xpos]).copy()

    def set_user_hands(self, user_hands: np.ndarray | None) -> None:
        """Show the user's hands (2, 3) as balls in the scene (None hides them)."""
        model, data = self._require()
        set_user_hands(model, data, user_hands)
        self._mujoco.mj_kinematics(model, data)

    def disconnect(self) -> None:
        self.model = None
        self.data = None
