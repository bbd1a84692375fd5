"""Safety by experience (Ito & Tani 2004, section 4.1; docs/safety.md): what unsafe means for
the humanoid (self-collision, servo speed, joint limits, motion that never settles), the
robot's exploration of its PB space, the meta-level network that learns PB → risk and
familiarity from it (stored beside the model), and the command filter that holds or slows an
unsafe command before it is sent.

Between the model and the robot: it imports :mod:`rnnpb.model` and :mod:`rnnpb.robot`; the
on-line step uses the risk network through :mod:`rnnpb.model.meta`, which knows no robot.
"""

from rnnpb.safety._attribute import GENERATION, SEEN, Attribution, asked_posture
from rnnpb.safety._check import (
    PHYSICAL,
    SafetyChecker,
    SafetyLimits,
    SequenceSafety,
    unsettled_steps,
)
from rnnpb.safety._data import DataSafety, as_written, check_data
from rnnpb.safety._explore import (
    Experience,
    ExplorationConfig,
    explore,
    generate_from,
    sample_pbs,
    sample_starts,
    visited,
)
from rnnpb.safety._filter import CommandFilter, FilterDecision
from rnnpb.safety._learn import learn_safety_map
from rnnpb.safety._map import (
    SAFETY_FORMAT,
    SAFETY_FORMAT_VERSION,
    SafetyMap,
    describe_safety_map,
    find_safety_map,
    load_safety_map,
    model_fingerprint,
    new_map,
    safety_map_path,
)
from rnnpb.safety._meta import MetaConfig, familiarity, fit_meta, init_meta, risk
from rnnpb.safety._online import OnlineSafety, online_safety, risk_plane, risk_views

__all__ = [
    "GENERATION",
    "SEEN",
    "Attribution",
    "asked_posture",
    "generate_from",
    "sample_starts",
    "new_map",
    "PHYSICAL",
    "SAFETY_FORMAT",
    "SAFETY_FORMAT_VERSION",
    "CommandFilter",
    "DataSafety",
    "as_written",
    "check_data",
    "Experience",
    "ExplorationConfig",
    "FilterDecision",
    "MetaConfig",
    "OnlineSafety",
    "SafetyChecker",
    "SafetyLimits",
    "SafetyMap",
    "SequenceSafety",
    "describe_safety_map",
    "explore",
    "familiarity",
    "find_safety_map",
    "fit_meta",
    "init_meta",
    "learn_safety_map",
    "load_safety_map",
    "model_fingerprint",
    "online_safety",
    "risk",
    "risk_plane",
    "risk_views",
    "safety_map_path",
    "sample_pbs",
    "unsettled_steps",
    "visited",
]
