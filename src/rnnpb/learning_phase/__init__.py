"""The paper's learning phase (section 2.1) for every source of a person's movement: the person
moves, the robot records the hands and its own joint angles for them, cut into whole cycles
(:func:`learning_phase`; docs/teaching.md, docs/design.md "One learning phase")."""

from rnnpb.learning_phase._cycles import (
    MAX_PERIOD,
    MIN_PERIOD,
    CycleCut,
    cycle_bounds,
    whole_cycles,
)
from rnnpb.learning_phase._framing import (
    FRAMINGS,
    MAX_DISTANCE,
    STANDARD_DISTANCE,
    Framing,
    choose_distance,
    frame_hands,
    placed_body,
    projected,
    reach_distance,
    resolve,
)
from rnnpb.learning_phase._performance import (
    Performance,
    Steps,
    from_capture,
    from_source,
    resampled,
    sensory_at,
)
from rnnpb.learning_phase._phase import (
    CUT_MODES,
    SEQUENCE_STEPS,
    SUBSTEPS,
    PhaseOptions,
    Recording,
    Retiming,
    fastest_cycle,
    learning_phase,
)
from rnnpb.learning_phase._playback import CaptureSource
from rnnpb.learning_phase._servos import SERVO_MARGIN, ServoFit, fit_to_servos

__all__ = [
    "CUT_MODES",
    "CaptureSource",
    "FRAMINGS",
    "MAX_DISTANCE",
    "MAX_PERIOD",
    "MIN_PERIOD",
    "SEQUENCE_STEPS",
    "SERVO_MARGIN",
    "SUBSTEPS",
    "STANDARD_DISTANCE",
    "CycleCut",
    "Framing",
    "Performance",
    "PhaseOptions",
    "Recording",
    "Retiming",
    "ServoFit",
    "Steps",
    "choose_distance",
    "cycle_bounds",
    "fastest_cycle",
    "fit_to_servos",
    "frame_hands",
    "from_capture",
    "from_source",
    "learning_phase",
    "placed_body",
    "projected",
    "reach_distance",
    "resampled",
    "resolve",
    "sensory_at",
    "whole_cycles",
]
