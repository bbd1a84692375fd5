"""The one grammar of source specifications (``--source``, ``rnnpb track SOURCE``, …).

=========================  ================================================================
``scenario:held:P``        the synthetic demonstrator keeps performing pattern ``P``
``scenario:pause:P``       pattern ``P`` with a 5-step pause in the middle (paper 3.1)
``scenario:switch:A,B,…``  the patterns one after another, 50 steps each (paper 3.2)
``scenario:novel:SET``     the pattern learning set ``SET`` left out (paper 3.3)
``scenario:routine:P*C,…`` a routine: pattern ``P`` for ``C`` cycles, then the next part,
                           with a person's timing (each part about 10 % longer or shorter)
``scenario:steps:M*N,…``   movements ``M`` (any demonstrator movement, or ``pause``) for ``N``
                           steps each, one after another: ``steps:1*60,random-walk*60``
``csv:FILE``               a sensory stream file (``step lhy lhz rhy rhz``; empty = not seen)
``video:FILE``             a video, through the colour-ball tracker
``images:DIR``             a folder of images, through the tracker
``webcam:INDEX``           a webcam, through the tracker
``synthetic:P``            a rendered synthetic camera of pattern ``P``, through the tracker
``zenoh:KEY[@ENDPOINT]``   hands published on a Zenoh bus by a camera node (docs/bridge.md)
``bvh:FILE[,FILE…]``       motion capture, as ``rnnpb record`` reads it, at the model's step
                           and framing (docs/motion-capture.md)
=========================  ================================================================

This module is the only place a spec string is taken apart: it sits above every kind of
source and opens each from its parts — scenarios from :mod:`rnnpb.demonstrator`, streams from
:mod:`rnnpb.sources`, cameras from :mod:`rnnpb.perception` (which opens a camera from
``kind, argument`` and reads no spec strings itself). Commands that take only cameras
(``rnnpb track``, ``rnnpb calibrate``) parse with ``kinds=CAMERA_KINDS``.

Camera sources deliver one observation per frame; a video or image folder recorded faster
than the network's step is sampled every ``frame_step``-th frame (for a video, by default the
frame nearest to each ``dt``).
"""

from __future__ import annotations

from dataclasses import dataclass

from rnnpb.errors import ConfigError, RnnpbError
from rnnpb.sources import CsvSensorySource, FrameStepSource, UserSource

SOURCE_FORMS = {
    "scenario": "scenario:held|pause|switch|novel|steps|routine:ARGUMENT",
    "csv": "csv:FILE",
    "video": "video:PATH",
    "images": "images:DIR",
    "webcam": "webcam:INDEX",
    "synthetic": "synthetic:PATTERN",
    "zenoh": "zenoh:KEY[@ENDPOINT]",
    "bvh": "bvh:FILE[,FILE...]",
}
"""Every kind of source, with the form of its spec string (for messages)."""

SOURCE_KINDS = tuple(SOURCE_FORMS)
CAMERA_KINDS = ("webcam", "video", "images", "synthetic")
"""The kinds read through a camera and the colour-ball tracker."""

SCENARIO_KINDS = ("held", "pause", "switch", "novel", "steps", "routine")


@dataclass(frozen=True)
class SourceSpec:
    """A parsed source specification.

    Attributes
    ----------
    kind : str
        One of :data:`SOURCE_KINDS`.
    argument : str or int
        What follows the first ``:`` — the device index (an int) for ``webcam``, the path, the
        pattern or the scenario (``held:1``) for the others.
    """

    kind: str
    argument: str | int


def parse_source_spec(spec: str, kinds: tuple[str, ...] = SOURCE_KINDS) -> SourceSpec:
    """``"webcam:0"`` → ``SourceSpec("webcam", 0)``; raises :class:`ConfigError`.

    Parameters
    ----------
    spec : str
        ``KIND:ARGUMENT`` (see the module doc). The kind is case-insensitive.
    kinds : tuple of str
        The kinds the caller takes (default all; ``CAMERA_KINDS`` for camera-only commands).
    """
    text = str(spec)
    forms = ", ".join(SOURCE_FORMS[kind] for kind in kinds)
    kind, sep, argument = text.partition(":")
    kind = kind.strip().lower()
    if not sep or not argument:
        raise ConfigError(f"source {text!r}: expected KIND:ARGUMENT, one of {forms}")
    if kind not in SOURCE_KINDS:
        raise ConfigError(f"source {text!r}: unknown kind {kind!r}; expected one of {forms}")
    if kind not in kinds:
        raise ConfigError(
            f"source {text!r}: a {kind} source cannot be used here; expected one of {forms}"
        )
    if kind == "webcam":
        try:
            return SourceSpec(kind, int(argument))
        except ValueError:
            raise ConfigError(f"source {text!r}: the webcam index must be an integer") from None
    return SourceSpec(kind, argument)


def parse_scenario(spec: str, seed: int = 0):
    """``held:1`` → the demonstrator's :class:`Scenario` (see the module doc)."""
    from rnnpb import demonstrator

    kind, _, argument = spec.partition(":")
    if kind not in SCENARIO_KINDS:
        raise ConfigError(
            f"unknown scenario {kind!r}: use one of {', '.join(k + ':…' for k in SCENARIO_KINDS)}"
        )
    if not argument:
        raise ConfigError(f"scenario {kind!r} needs an argument, e.g. scenario:{kind}:1")
    try:
        if kind == "held":
            return demonstrator.held_scenario(argument, seed=seed)
        if kind == "pause":
            return demonstrator.pause_scenario(argument, seed=seed)
        if kind == "switch":
            return demonstrator.switch_scenario(tuple(argument.split(",")), seed=seed)
        if kind == "steps":
            return demonstrator.make_scenario(_segments(argument), seed=seed)
        if kind == "routine":
            return demonstrator.routine_scenario(parse_routine(argument), seed=seed)
        return demonstrator.novel_scenario(argument, seed=seed)
    except (KeyError, ValueError) as error:
        if isinstance(error, RnnpbError):
            raise
        raise ConfigError(f"scenario {spec!r}: {error}") from None


def _segments(argument: str, what: str = "steps", unit: str = "STEPS") -> list[tuple[str, int]]:
    """``"1*60,pause*10"`` → ``[("1", 60), ("pause", 10)]``."""
    segments = []
    for part in argument.split(","):
        name, star, count = part.strip().rpartition("*")
        if not star or not name:
            raise ConfigError(f"scenario {what}: expected MOVEMENT*{unit}, got {part!r}")
        try:
            n = int(count)
        except ValueError:
            raise ConfigError(
                f"scenario {what}: {part!r}: {unit.lower()} must be an integer"
            ) from None
        if n < 1:
            raise ConfigError(f"scenario {what}: {part!r}: {unit.lower()} must be >= 1")
        segments.append((name.strip().lower(), n))
    return segments


def parse_routine(argument: str) -> list[tuple[str, int]]:
    """``"1*3,3*2"`` → ``[("1", 3), ("3", 2)]``: patterns and their cycles."""
    parts = []
    for name, count in _segments(argument, "routine", "CYCLES"):
        if name == "pause":
            raise ConfigError("scenario routine: a routine is made of movements, not pauses")
        parts.append((name, count))
    return parts


def open_source(
    spec: str,
    *,
    seed: int = 0,
    dt: float = 0.4,
    frame_step: int | None = None,
    colors: str | None = None,
    steps: int | None = None,
    perception: str = "balls",
    framing: float | None = None,
    time_scale: float = 1.0,
) -> UserSource:
    """Open the user source a specification string names (see the module doc).

    Parameters
    ----------
    spec : str
    seed : int
        Seed of the scenario or the synthetic camera.
    dt : float
        Seconds per network step (a video's default ``frame_step`` is its fps × dt).
    frame_step : int, optional
        Keep every N-th camera frame.
    colors : path of a colour file, optional
        Ball colours for camera sources.
    steps : int, optional
        At most this many camera frames (the synthetic camera renders this many).
    perception : str
        How a camera's frames become hands: ``"balls"`` (the colour-ball tracker) or
        ``"pose"`` (bare hands, the pose model of ``rnnpb[hands]``). Camera sources only.
    framing : float, optional
        Metres from the robot at which a person's body is placed in the camera's view (the
        model's framing: :mod:`rnnpb.learning_phase`), for sources that know the body (bare
        hands, motion capture); None: the standard user's place.
    time_scale : float
        Motion capture: play it this many times slower.
    """
    parsed = parse_source_spec(spec)
    if perception != "balls" and parsed.kind not in CAMERA_KINDS:
        raise ConfigError(
            f"--perception {perception} applies to camera sources "
            f"({', '.join(CAMERA_KINDS)}), not to {parsed.kind}"
        )
    if parsed.kind == "scenario":
        from rnnpb.demonstrator import ScenarioSource

        return ScenarioSource(parse_scenario(str(parsed.argument), seed))
    if parsed.kind == "csv":
        return CsvSensorySource(str(parsed.argument))
    if parsed.kind == "bvh":
        from rnnpb.learning_phase import STANDARD_DISTANCE, CaptureSource

        files = [f.strip() for f in str(parsed.argument).split(",")]
        if not all(files):
            raise ConfigError(f"source {spec!r}: expected bvh:FILE[,FILE...]")
        distance = STANDARD_DISTANCE if framing is None else framing
        return CaptureSource(files, dt, distance, time_scale)
    if parsed.kind == "zenoh":
        from rnnpb.bridge import ZenohHandsSource, parse_bus_spec

        key, bus = parse_bus_spec(spec, "", "source")
        if not key:
            raise ConfigError(f"source {spec!r}: name the key the hands are published on")
        return ZenohHandsSource(key, dt=dt, bus=bus)
    from rnnpb.perception import open_camera_source

    pose_config = None
    if perception == "pose" and framing is not None:
        from rnnpb.learning_phase import placed_body
        from rnnpb.perception import PoseConfig

        pose_config = PoseConfig(body=placed_body(framing))
    source = open_camera_source(
        parsed.kind,
        parsed.argument,
        colors=colors,
        steps=steps,
        seed=seed,
        perception=perception,
        pose_config=pose_config,
    )
    if frame_step is None and parsed.kind == "video":
        frame_step = _video_frame_step(str(parsed.argument), dt)
    if frame_step and frame_step > 1:
        return FrameStepSource(source, frame_step)
    return source


def _video_frame_step(path: str, dt: float) -> int:
    from rnnpb.perception import video_fps

    fps = video_fps(path)
    return max(1, round(fps * dt)) if fps else 1
