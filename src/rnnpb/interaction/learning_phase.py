"""The paper's learning phase (section 2.1, Fig. 2a) from any user source: the person moves,
the robot records the hands and its own joint angles for them, cut into whole cycles.

Per step: the hands' 3-D positions — from the colour balls' image centres and apparent sizes
for a camera source (:func:`rnnpb.perception.hands_from_balls`), on a fixed plane in front of
the robot for a source without depth (:func:`rnnpb.perception.hands_on_plane`) — then the
robot's hand targets by the mirror mapping and its joint angles by the safe retargeting
(:class:`rnnpb.demonstrator.MirrorMapping`, :func:`rnnpb.robot.retarget`). The sensory values
are the ones the source measured (the network is taught what the camera sees, as in the paper).

Cutting (:func:`cycle_bounds`): the first principal component of the sensory values, lightly
smoothed, crosses its mean upwards once per cycle of any of the paper's patterns; cycles are
the stretches between successive upward crossings at least half the dominant period apart (the
period from the autocorrelation's first peak, :func:`rnnpb.structure.first_period`). A
sequence is then ``cycles_per_sequence`` whole cycles (``mode="cycles"``) or consecutive
windows of ``length`` steps (``mode="length"``) or each stretch whole (``mode="whole"``, a
routine);
steps where a hand could not be recovered (lost longer than the gap filling covers) split the
recording, and a sequence never spans them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rnnpb.demonstrator import MirrorMapping
from rnnpb.errors import ConfigError, RnnpbError
from rnnpb.perception import (
    MOUSE_PLANE_X,
    DepthConfig,
    TrackedUserSource,
    hands_from_balls,
    hands_from_pose,
    hands_on_plane,
)
from rnnpb.robot.camera import RobotCamera
from rnnpb.sequences import Sequence
from rnnpb.sources import FrameStepSource, UserSource
from rnnpb.structure import first_period

CUT_MODES = ("cycles", "length", "whole")
MIN_PERIOD = 4
MAX_PERIOD = 60


@dataclass(frozen=True)
class Demonstration:
    """A recorded demonstration, step by step.

    Attributes
    ----------
    sensory : array, shape (n_steps, 4)
        What the source measured, ``lhy lhz rhy rhz``; NaN where a hand was not seen.
    hands : array, shape (n_steps, 2, 3)
        The user's hands in the robot frame, metres; NaN where not recovered.
    motor : array, shape (n_steps, 8)
        The robot's joint angles for them, radians; NaN where the hands are NaN.
    ik_residual : array, shape (n_steps, 2)
        Distance from each robot hand target to where the arm reaches, metres.
    depth : str
        ``"size"`` (from the balls' apparent size), ``"pose"`` (the pose model's wrist depth,
        scaled by the shoulder span), ``"plane"`` (the fixed plane) or ``"3-d"`` (given in 3-D:
        motion capture).
    source : str
        The source's description.
    adjusted : array of bool, shape (n_steps,)
        Steps where the paper's inverse kinematics was unsafe and the safe retargeting moved
        the arms to the closest safe posture.
    """

    sensory: np.ndarray
    hands: np.ndarray
    motor: np.ndarray
    ik_residual: np.ndarray
    depth: str
    source: str = ""
    truth: dict = field(default_factory=dict, compare=False)
    adjusted: np.ndarray = field(default_factory=lambda: np.zeros(0, bool), compare=False)

    @property
    def n_steps(self) -> int:
        return int(len(self.sensory))

    @property
    def valid(self) -> np.ndarray:
        """Steps whose sensory and motor values are all finite, shape (n_steps,)."""
        return np.asarray(
            np.isfinite(self.sensory).all(axis=1) & np.isfinite(self.motor).all(axis=1)
        )


def record_demonstration(
    source: UserSource,
    *,
    steps: int | None = None,
    mapping: MirrorMapping | None = None,
    camera: RobotCamera | None = None,
    depth: DepthConfig | None = None,
    plane_x: float = MOUSE_PLANE_X,
) -> Demonstration:
    """Read a connected source to its end (or ``steps``) and turn it into a demonstration.

    A :class:`rnnpb.perception.TrackedUserSource` gives depth from the balls' sizes (or, with
    the pose tracker, from the wrists' depth scaled by the shoulder span); every other source
    puts the hands on the plane ``x = plane_x``.
    """
    if steps is not None and steps < 2:
        raise ConfigError(f"a demonstration needs at least 2 steps, got {steps}")
    mapping = mapping or MirrorMapping()
    camera = camera or RobotCamera()
    # A video sampled every N-th frame: read the tracker's frames here, so that each kept
    # observation is paired with its own ball sizes (not those of the last dropped frame).
    frame_step = 1
    reader = source
    if isinstance(source, FrameStepSource) and isinstance(source.inner, TrackedUserSource):
        reader, frame_step = source.inner, source.frame_step
    tracked = isinstance(reader, TrackedUserSource)
    posed = isinstance(reader, TrackedUserSource) and reader.perception == "pose"
    sensory, centers, radii, posed_hands, frame_size = [], [], [], [], None
    index = -1
    while steps is None or len(sensory) < steps:
        observation = reader.read()
        if observation is None:
            break
        index += 1
        if index % frame_step:
            continue
        sensory.append(observation.sensory)
        if isinstance(reader, TrackedUserSource):
            result = reader.last_result
            assert result is not None
            posed_hands.append(result.hands_3d)
            centers.append([ball.center_px for ball in result.balls])
            radii.append([ball.radius_px for ball in result.balls])
            if observation.frame is not None:
                frame_size = (observation.frame.shape[1], observation.frame.shape[0])
    if len(sensory) < 2:
        raise RnnpbError(
            f"{_described(source)}: gave {len(sensory)} steps; a demonstration needs at least 2"
        )
    sensory_array = np.array(sensory)
    if posed:
        hands = hands_from_pose(np.array(posed_hands), depth)
    elif tracked:
        hands = hands_from_balls(
            np.array(centers), np.array(radii), camera, depth, image_size=frame_size
        )
    else:
        hands = hands_on_plane(sensory_array, camera, plane_x)
    motor, residual, adjusted = _motor_for_hands(mapping, hands)
    return Demonstration(
        sensory_array,
        hands,
        motor,
        residual,
        "pose" if posed else "size" if tracked else "plane",
        _described(source),
        adjusted=adjusted,
    )


def demonstration_from_hands(
    hands: np.ndarray,
    *,
    mapping: MirrorMapping | None = None,
    camera: RobotCamera | None = None,
    source: str = "",
) -> Demonstration:
    """A demonstration from the user's 3-D hands (motion capture): the sensory values are
    what the robot's camera sees of them, the motor values come through the mirror mapping as
    in :func:`record_demonstration`.

    ``hands`` shape (n_steps, 2, 3), robot frame, metres; NaN where a hand is not known. A
    hand outside the camera's view is not seen (NaN sensory values), as with a camera.
    """
    hands = np.asarray(hands, dtype=np.float64)
    if hands.ndim != 3 or hands.shape[1:] != (2, 3) or len(hands) < 2:
        raise ConfigError(f"a demonstration needs hands of shape (n >= 2, 2, 3), got {hands.shape}")
    sensory = (camera or RobotCamera()).sensory_from_hands(hands).reshape(-1, 2, 2)
    with np.errstate(invalid="ignore"):
        sensory[((sensory < 0) | (sensory > 1)).any(axis=2)] = np.nan
    sensory = sensory.reshape(-1, 4)
    motor, residual, adjusted = _motor_for_hands(mapping or MirrorMapping(), hands)
    return Demonstration(sensory, hands, motor, residual, "3-d", source, adjusted=adjusted)


def _motor_for_hands(
    mapping: MirrorMapping, hands: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The robot's joint angles (n, 8), each hand's reach residual (n, 2) and the steps the
    retargeting moved to a safe posture (n,) for the user's hands (n, 2, 3); NaN where a hand
    is not known. Every demonstration's motor values come
    from here: the safe retargeting (:meth:`MirrorMapping.retarget`), which starts again
    after a lost hand."""
    result = mapping.retarget(hands)
    return result.joints, result.residual, result.adjusted


def _described(source: UserSource) -> str:
    return str(getattr(source, "description", "") or type(source).__name__)


def dominant_period(
    signal: np.ndarray, min_period: int = MIN_PERIOD, max_period: int = MAX_PERIOD
) -> int | None:
    """The lag of the autocorrelation's first strong peak in [min_period, max_period], or None
    when the signal does not repeat (:func:`rnnpb.structure.first_period`: a peak above 0.3
    and at least 0.6 above the lowest correlation at a shorter lag, the first within 0.8 of
    the highest). ``signal`` shape (n_steps,)."""
    return first_period(signal, min_period, max_period, level=0.3, rise=0.6, share=0.8)


def cycle_bounds(sensory: np.ndarray) -> list[tuple[int, int]]:
    """Whole cycles of a movement, as ``[(start, stop), …]`` step ranges (stop exclusive).

    ``sensory`` shape (n_steps, 4), all finite. Empty when the movement does not repeat.
    """
    x = np.asarray(sensory, dtype=np.float64)
    if x.ndim != 2 or len(x) < 2 * MIN_PERIOD or not np.isfinite(x).all():
        return []
    centred = x - x.mean(axis=0)
    _, _, vt = np.linalg.svd(centred, full_matrices=False)
    component = centred @ vt[0]
    component = np.convolve(np.pad(component, 1, mode="edge"), np.ones(3) / 3, mode="valid")
    period = dominant_period(component)
    if period is None:
        return []
    ups = np.where((component[:-1] < 0) & (component[1:] >= 0))[0] + 1
    starts: list[int] = []
    for t in ups:
        if not starts or t - starts[-1] >= period / 2:
            starts.append(int(t))
    return list(zip(starts[:-1], starts[1:], strict=True))


def _valid_runs(valid: np.ndarray) -> list[tuple[int, int]]:
    edges = np.diff(np.concatenate([[0], valid.astype(int), [0]]))
    return list(zip(np.where(edges == 1)[0], np.where(edges == -1)[0], strict=True))


def cut_sequences(
    demonstration: Demonstration,
    pattern: str,
    *,
    mode: str = "cycles",
    cycles_per_sequence: int = 4,
    length: int = 50,
) -> list[Sequence]:
    """Cut a demonstration into training sequences of ``pattern`` (see the module doc).

    Raises :class:`RnnpbError` when nothing whole is left to cut (no repeating movement, or
    every stretch shorter than asked).
    """
    if mode not in CUT_MODES:
        raise ConfigError(f"cut mode must be one of {', '.join(CUT_MODES)}, got {mode!r}")
    if cycles_per_sequence < 1:
        raise ConfigError(f"cycles_per_sequence must be >= 1, got {cycles_per_sequence}")
    if length < 2:
        raise ConfigError(f"sequence length must be >= 2, got {length}")
    sequences: list[Sequence] = []
    for start, stop in _valid_runs(demonstration.valid):
        if mode == "whole":
            pieces = [(start, stop)] if stop - start >= 2 else []
        elif mode == "length":
            pieces = [(s, s + length) for s in range(start, stop - length + 1, length)]
        else:
            cycles = cycle_bounds(demonstration.sensory[start:stop])
            pieces = [
                (start + cycles[i][0], start + cycles[i + cycles_per_sequence - 1][1])
                for i in range(0, len(cycles) - cycles_per_sequence + 1, cycles_per_sequence)
            ]
        for a, b in pieces:
            sequences.append(
                Sequence(
                    demonstration.sensory[a:b],
                    demonstration.motor[a:b],
                    pattern,
                    f"{demonstration.source} steps {a}-{b - 1}",
                    meta={"hands": demonstration.hands[a:b], "first_step": a},
                )
            )
    if not sequences:
        what = f"{cycles_per_sequence} whole cycles" if mode == "cycles" else f"{length} steps"
        raise RnnpbError(
            f"{demonstration.source}: no stretch of {what} with both hands seen "
            f"in {demonstration.n_steps} steps (is the movement repeating?)"
        )
    return sequences
