"""Incremental learning: rehearsal and consolidation (Ito & Tani 2004, section 4.1, after
Tani 1998).

Every memory of an RNNPB shares the same weights, so learning a new pattern alone overwrites
the old ones (the memory interference problem). The paper's remedy: the network, as long-term
memory, *rehearses* what it knows — it regenerates each learned pattern in closed loop from
that pattern's PB, with no access to the original data — and is then trained on the new
pattern together with the rehearsed ones (*consolidation*).

:func:`consolidate` runs it, and the alternatives it is measured against, through the same
learning (:mod:`rnnpb.model.learning`, driven by :func:`rnnpb.model.training.train`, with its
progress, checkpoints and resume):

``rehearsal``
    the new sequences and one rehearsed sequence per learned sequence (:func:`rehearse`: by
    default stretches of each pattern's limit cycle, generated from the pattern's PB); by
    default a rehearsed sequence learns the old network's function on it — what the model
    predicts from the sequence's noisy inputs — rather than its own next steps (a trajectory
    target pulls every noisy input back onto the cycle and loses the network's response to a
    person's version of the pattern, and with it lock-on);
``finetune``
    the new sequences alone: what interference looks like;
``replay``
    the new sequences and the stored original data (the caller passes it: the model file keeps
    only its fingerprint);
``scratch``
    the original data and the new sequences learned anew from random weights, with the
    model's own full learning: the upper bound.

All but ``scratch`` start from the model's weights ("warm start"); an old sequence starts from
its learned PB and initial context (held there for the first half when adding patterns), a new
sequence from context 0.5 and, when adding patterns, the PB farthest from the learned ones (it
need not push the old patterns' PBs aside). The old patterns keep their names, the new pattern
gets PBs of its own, and the result records the step in its history
(:class:`rnnpb.model.io.HistoryEntry`).

**One policy.** What a consolidation does when the caller does not say — its iterations, the
least input noise, the PB hold, the new PB's start, the rehearsal — is data: the
``[consolidation]`` section of the model's learning preset (:mod:`rnnpb.presets`, each value
with its evidence), with its ``[teaching]`` section over it when on-line teaching learns a
kept episode. :func:`consolidation_config` (``purpose="add"`` or ``"teach"``) is how
``rnnpb consolidate``, teaching and the studies get it. For research, ``--config FILE``
changes the preset's values, and a choice set by :meth:`ConsolidationConfig.with_tuning` wins
over the policy's.

Unlike the rest of the model this module reads a clock: the time the history records.
"""

from __future__ import annotations

import datetime
import os
from collections.abc import Callable, Mapping
from collections.abc import Sequence as SequenceABC
from dataclasses import InitVar, dataclass, field, replace
from pathlib import Path
from typing import Any, Literal, get_args

import numpy as np

from rnnpb.errors import ConfigError, DataFileError
from rnnpb.model._tuned import Tuning, settle, tuned_names
from rnnpb.model._tuned import with_tuning as _with_tuning
from rnnpb.model.generation import generate
from rnnpb.model.io import HistoryEntry, TrainedModel
from rnnpb.model.learning import TrainConfig, WarmStart, prepare_data
from rnnpb.model.training import TrainingProgress, train
from rnnpb.presets import Overrides, Preset, load_preset
from rnnpb.sequences import Sequence

Method = Literal["rehearsal", "finetune", "replay", "scratch"]
CONSOLIDATION_METHODS: tuple[str, ...] = get_args(Method)
"""The ways :func:`consolidate` adds patterns (see the module)."""
Purpose = Literal["add", "teach"]
PURPOSES: tuple[str, ...] = get_args(Purpose)
"""What a consolidation is for: adding recorded patterns (``rnnpb consolidate``, the
incremental study), or learning an episode kept on-line by teaching."""
HoldOldPB = Literal["off", "all", "first-half"]
HOLD_OLD_PB_OPTIONS: tuple[str, ...] = get_args(HoldOldPB)
"""How long a consolidation keeps the old sequences' PBs at their learned values:
never (they learn by eqs. 1–2 with the new ones), for all of it, or for its first half."""
NewPBStart = Literal["centre", "farthest"]
NEW_PB_STARTS: tuple[str, ...] = get_args(NewPBStart)
"""Where a new sequence's PB starts: at 0.5 like a first training's, or at the point of a grid
of PB space farthest from the learned patterns' PBs (:func:`farthest_pb`)."""
RehearsalTarget = Literal["function", "trajectory"]
REHEARSAL_TARGETS: tuple[str, ...] = get_args(RehearsalTarget)
"""What a rehearsed sequence learns towards: the old network's *function* — what the model,
from the pattern's PB and the stretch's context, predicts for the same noisy teacher-forced
inputs — or the rehearsed *trajectory*'s own next steps."""
RehearsalSource = Literal["patterns", "sequences"]
REHEARSAL_SOURCES: tuple[str, ...] = get_args(RehearsalSource)
"""What :func:`rehearse` runs the closed loop from: each pattern's PB, or each sequence's."""


@dataclass(frozen=True)
class ConsolidationPolicy:
    """The measured choices of a consolidation of one model for one purpose: its learning
    preset's ``[consolidation]`` section, with the ``[teaching]`` section over it for
    ``"teach"`` (each value's reason is its evidence in the preset file).

    Attributes
    ----------
    iterations : int
        Learning iterations from the model's weights.
    input_noise : float
        The least noise (standard deviation, normalized units) on the teacher-forced inputs:
        it holds an old pattern's closed loop on its cycle while the weights move for the new
        one (a model learned with more keeps its own).
    function_rehearsal_input_noise : float
        The same for a rehearsal of the old network's function, which is learned where the
        noise brings the inputs: near each cycle, as far as a person's version of it.
    hold_old_pb, new_pb_start, rehearsal_target, rehearsal_source : str
    rehearsal_steps, rehearsal_transient : int
        What :class:`ConsolidationConfig`'s fields of those names are when left None, and
        :func:`rehearse`'s defaults.
    """

    iterations: int
    input_noise: float
    function_rehearsal_input_noise: float
    hold_old_pb: HoldOldPB
    new_pb_start: NewPBStart
    rehearsal_target: RehearsalTarget
    rehearsal_source: RehearsalSource
    rehearsal_steps: int
    rehearsal_transient: int

    def least_input_noise(self, method: str, rehearsal_target: str) -> float:
        """The least input noise of a consolidation by ``method`` (rehearsing towards
        ``rehearsal_target``)."""
        if method == "rehearsal" and rehearsal_target == "function":
            return self.function_rehearsal_input_noise
        return self.input_noise


def recorded_learning(model: TrainedModel) -> TrainConfig:
    """The learning ``model`` recorded (the paper's algorithm for a model that recorded none)."""
    recorded = model.meta.get("train_config")
    try:
        return (
            TrainConfig.from_dict(recorded) if isinstance(recorded, dict) else TrainConfig.paper()
        )
    except (TypeError, ValueError, KeyError) as error:
        raise ConfigError(
            f"the model's recorded training config is not usable ({error}); "
            "give the consolidation's learning explicitly"
        ) from None


def _learning_preset(model: TrainedModel, overrides: Overrides | None = None) -> Preset:
    """The learning preset the model was learned with (:attr:`TrainedModel.learning_preset`;
    the paper's for a model that recorded no learning), with ``overrides`` over it."""
    recorded = model.learning_preset
    name = recorded[0] if recorded is not None else "paper"
    return load_preset(name) if overrides is None else overrides.preset(name)


def consolidation_policy(
    model: TrainedModel, purpose: Purpose = "add", preset: Preset | None = None
) -> ConsolidationPolicy:
    """How ``model`` is consolidated for ``purpose`` (one of :data:`PURPOSES`): the values of
    ``preset``, by default the learning preset the model was learned with.

    Teaching learns a kept episode — three cycles of an imperfect demonstration — into the
    model while the person goes on: the ``[teaching]`` section sets its own iterations, new PB
    start and PB hold, and its input noise is a floor over the consolidation's (a person's
    version of an old pattern can lie further from its cycle than that noise reaches).
    """
    if purpose not in PURPOSES:
        raise ConfigError(
            f"consolidation purpose must be one of {', '.join(PURPOSES)}, got {purpose!r}"
        )
    preset = preset or _learning_preset(model)
    values = dict(preset.section("consolidation"))
    if purpose == "teach":
        teaching = preset.section("teaching")
        floor = teaching["input_noise"]
        values.update(
            iterations=teaching["iterations"],
            hold_old_pb=teaching["hold_old_pb"],
            new_pb_start=teaching["new_pb_start"],
            input_noise=max(values["input_noise"], floor),
            function_rehearsal_input_noise=max(values["function_rehearsal_input_noise"], floor),
        )
    try:
        return ConsolidationPolicy(**values)
    except TypeError as error:
        raise ConfigError(f"preset {preset.name!r}: [consolidation] {error}") from None


_UNRESOLVED = Tuning(
    "model",
    dict.fromkeys(
        (
            "rehearsal_steps",
            "rehearsal_transient",
            "rehearsal_source",
            "hold_old_pb",
            "new_pb_start",
            "rehearsal_target",
        )
    ),
)
"""A :class:`ConsolidationConfig`'s tuned values before :meth:`~ConsolidationConfig.resolved`:
each None, the model's policy's."""


@dataclass(frozen=True)
class ConsolidationConfig:
    """How to add patterns to a learned model.

    A user names the method (and, if not the model's own, the learning). The rest — the
    rehearsal, the PB hold, the new PB's start — is the model's :func:`consolidation_policy`
    for ``purpose``: those fields are read-only (``init=False``), None until :meth:`resolved`
    takes them from the policy, and changed only by :meth:`with_tuning`, for research:
    ``ConsolidationConfig().with_tuning(hold_old_pb="all")`` holds the old PBs whatever the
    policy says (``--config FILE``'s ``[consolidation]`` table changes the policy itself:
    :func:`consolidation_config`).

    Attributes
    ----------
    method : str
        One of :data:`CONSOLIDATION_METHODS`.
    purpose : str
        One of :data:`PURPOSES`: whose measured choices the fields left None take.
    train : TrainConfig or None
        The learning. None: the model's own recorded learning (its optimizer, rates and seed)
        with the policy's iterations and at least its input noise — for ``scratch`` the
        model's own full learning, unchanged.
    rehearsal_steps, rehearsal_transient : int or None
        Length of each rehearsed sequence, and the closed-loop steps run before it (tuned).
    rehearsal_source : str or None
        What :func:`rehearse` runs the closed loop from (:data:`REHEARSAL_SOURCES`; tuned).
    hold_old_pb : str or None
        One of :data:`HOLD_OLD_PB_OPTIONS`: whether the old sequences' PBs stay at their
        learned values while the weights learn the new pattern — ``"all"`` of the
        consolidation, its ``"first-half"`` (while the new pattern's error is largest), or
        ``"off"``. The new sequences' PBs always learn. For ``rehearsal`` and ``replay``, the
        methods that learn old sequences from their learned PBs; ``finetune`` learns no old
        sequence and ``scratch`` has no learned PB to hold, so neither uses it (tuned).
    new_pb_start : str or None
        One of :data:`NEW_PB_STARTS`: where the new sequences' PBs start (every warm-started
        method; ``scratch`` starts everything anew; tuned).
    rehearsal_target : str or None
        One of :data:`REHEARSAL_TARGETS`: what ``rehearsal``'s rehearsed sequences learn
        towards (tuned).
    """

    method: Method = "rehearsal"
    purpose: Purpose = "add"
    train: TrainConfig | None = None
    rehearsal_steps: int | None = field(default=None, init=False)
    rehearsal_transient: int | None = field(default=None, init=False)
    rehearsal_source: RehearsalSource | None = field(default=None, init=False)
    hold_old_pb: HoldOldPB | None = field(default=None, init=False)
    new_pb_start: NewPBStart | None = field(default=None, init=False)
    rehearsal_target: RehearsalTarget | None = field(default=None, init=False)
    _tuning: InitVar[Mapping[str, Any] | None] = None

    def __post_init__(self, _tuning: Mapping[str, Any] | None) -> None:
        settle(self, _tuning, _UNRESOLVED, None)
        for name, value, allowed in (
            ("consolidation method", self.method, CONSOLIDATION_METHODS),
            ("consolidation purpose", self.purpose, PURPOSES),
            ("rehearsal_source", self.rehearsal_source, (None, *REHEARSAL_SOURCES)),
            ("new_pb_start", self.new_pb_start, (None, *NEW_PB_STARTS)),
            ("rehearsal_target", self.rehearsal_target, (None, *REHEARSAL_TARGETS)),
            ("hold_old_pb", self.hold_old_pb, (None, *HOLD_OLD_PB_OPTIONS)),
        ):
            if value not in allowed:
                choices = ", ".join(a for a in allowed if a is not None)
                raise ConfigError(f"{name} must be one of {choices}, got {value!r}")
        if self.rehearsal_steps is not None and self.rehearsal_steps < 2:
            raise ConfigError(f"rehearsal_steps must be >= 2, got {self.rehearsal_steps}")
        if self.rehearsal_transient is not None and self.rehearsal_transient < 1:
            raise ConfigError(f"rehearsal_transient must be >= 1, got {self.rehearsal_transient}")

    def with_tuning(self, **changes: Any) -> ConsolidationConfig:
        """This config with some of the policy's choices made here, for research: e.g.
        ``ConsolidationConfig().with_tuning(hold_old_pb="all")`` (None gives one back to
        the policy)."""
        return _with_tuning(self, changes)

    def resolved(self, model: TrainedModel, preset: Preset | None = None) -> ConsolidationConfig:
        """This config with every field left None taken from ``model``'s policy for
        :attr:`purpose` (from ``preset``, by default the model's), and its learning
        (:meth:`learning_for`)."""
        policy = consolidation_policy(model, self.purpose, preset)
        chosen = {
            name: getattr(policy, name) if getattr(self, name) is None else getattr(self, name)
            for name in tuned_names(ConsolidationConfig)
        }
        return replace(self.with_tuning(**chosen), train=self.learning_for(model, preset))

    def learning_for(self, model: TrainedModel, preset: Preset | None = None) -> TrainConfig:
        """The :class:`TrainConfig` this consolidation of ``model`` learns with (the policy's
        from ``preset``, by default the model's)."""
        if self.train is not None:
            return self.train
        own = recorded_learning(model)
        if self.method == "scratch":
            # The first training's length: a consolidated model records its consolidation's.
            first = model.history[0].train_config.get("iterations")
            return replace(own, iterations=first) if isinstance(first, int) else own
        policy = consolidation_policy(model, self.purpose, preset)
        target = self.rehearsal_target or policy.rehearsal_target
        least = policy.least_input_noise(self.method, target)
        return replace(own, iterations=policy.iterations, input_noise=max(own.input_noise, least))


def consolidation_config(
    model: TrainedModel,
    purpose: Purpose = "add",
    *,
    method: Method = "rehearsal",
    iterations: int | None = None,
    seed: int | None = None,
    overrides: Overrides | None = None,
) -> ConsolidationConfig:
    """The consolidation of ``model`` for ``purpose``, every choice made: the one policy
    ``rnnpb consolidate``, on-line teaching and the studies consolidate by.

    ``iterations`` and ``seed``, given, replace the policy's and the model's. ``overrides``
    (a ``--config`` file: its ``[consolidation]`` and ``[teaching]`` tables) go over the
    preset the policy reads; an unknown key is a :class:`ConfigError`.
    """
    preset = _learning_preset(model, overrides)
    config = ConsolidationConfig(method=method, purpose=purpose).resolved(model, preset)
    assert config.train is not None
    changes = {"iterations": iterations, "seed": seed}
    learning = replace(config.train, **{k: v for k, v in changes.items() if v is not None})
    return replace(config, train=learning)


def _taught(model: TrainedModel, learned: TrainedModel, n_new: int) -> np.ndarray | None:
    """The consolidated model's hands as taught, for a rehearsal or a fine-tuning (one old
    sequence each of the model's, in its order, then the new): the old sequences keep the
    hands they were first taught with (a rehearsal learned the network's own generation, not
    what the user showed), the new ones are their data's. None when the old model kept none."""
    if model.taught_sensory is None or learned.taught_sensory is None:
        return None
    old, new = model.taught_sensory, learned.taught_sensory[len(learned.taught_sensory) - n_new :]
    steps = max(old.shape[1], new.shape[1])
    padded = [
        np.pad(a, ((0, 0), (0, steps - a.shape[1]), (0, 0)), constant_values=np.nan)
        for a in (old, new)
    ]
    return np.concatenate(padded)


FARTHEST_PB_CANDIDATES = 20_000
"""Most candidate points :func:`farthest_pb` weighs."""


def farthest_pb(learned: np.ndarray, levels: int = 5) -> np.ndarray:
    """The point of a grid of PB space (``levels`` values per dimension from 0.1 to 0.9) whose
    nearest learned PB (rows of ``learned``) is farthest; ties go to the grid's first. A PB
    space too large for such a grid (more than :data:`FARTHEST_PB_CANDIDATES` points) is
    searched over that many points drawn uniformly in the same box with a fixed seed."""
    learned = np.atleast_2d(np.asarray(learned, dtype=np.float64))
    n_dims = learned.shape[1]
    if levels**n_dims <= FARTHEST_PB_CANDIDATES:
        axes = [np.linspace(0.1, 0.9, levels)] * n_dims
        grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, n_dims)
    else:
        grid = np.random.default_rng(0).uniform(0.1, 0.9, (FARTHEST_PB_CANDIDATES, n_dims))
    nearest = np.min(np.linalg.norm(grid[:, None, :] - learned[None, :, :], axis=-1), axis=1)
    return grid[int(np.argmax(nearest))]


def model_joint_limits(model: TrainedModel) -> np.ndarray:
    """The motor normalization of ``model`` as joint limits (M, 2): a consolidation keeps the
    model's normalization, so its weights mean what they meant."""
    s = model.network.sensory_size
    return np.column_stack([model.lower[s:], model.upper[s:]])


def rehearse(
    model: TrainedModel,
    n_steps: int | None = None,
    transient: int | None = None,
    source: RehearsalSource | None = None,
) -> list[Sequence]:
    """Each learned pattern regenerated in closed loop, without the original data: one
    rehearsed sequence per learned sequence (what is not given: the model's
    :func:`consolidation_policy`).

    ``source="patterns"``: each pattern's closed loop runs from the pattern's PB and initial
    context (what generation and recognition use: :attr:`TrainedModel.pattern_pb`); a
    pattern with k learned sequences gives k consecutive stretches of ``n_steps`` of that run,
    after ``transient`` steps. ``source="sequences"``: each learned sequence's closed loop runs
    from its own PB and initial context and gives its last ``n_steps`` after ``transient``.
    Either way ``meta["initial_context"]`` (C,) is the context the network had at the
    rehearsed sequence's first step and ``meta["pb"]`` (P,) the PB it ran with: learning from
    them, the network already predicts the rehearsed sequence exactly.

    Returns
    -------
    list of Sequence
        One per learned sequence, in the model's order, each named by its pattern (raw units:
        sensory in [0, 1], motor in radians).
    """
    if n_steps is None or transient is None or source is None:
        policy = consolidation_policy(model)
        n_steps = policy.rehearsal_steps if n_steps is None else n_steps
        transient = policy.rehearsal_transient if transient is None else transient
        source = policy.rehearsal_source if source is None else source
    if n_steps < 2 or transient < 1:
        raise ConfigError(
            f"rehearsal needs n_steps >= 2 and transient >= 1, got {n_steps} and {transient}"
        )
    if source not in REHEARSAL_SOURCES:
        raise ConfigError(
            f"rehearsal source must be one of {', '.join(REHEARSAL_SOURCES)}, got {source!r}"
        )
    names = list(model.sequence_patterns)
    out = []
    for i, pattern in enumerate(names):
        if source == "patterns":
            k = names[:i].count(pattern)  # this pattern's k-th sequence: its k-th stretch
            pb = model.pattern_pb[pattern]
            context = model.pattern_initial_context(pattern)
            label = f"rehearsed pattern {pattern} (stretch {k + 1})"
        else:
            k = 0
            pb = model.sequence_pb[i]
            context = model.initial_context[i]
            label = f"rehearsed pattern {pattern} (sequence {i + 1})"
        first = transient + k * n_steps
        generated = generate(model, pb, first - 1 + n_steps, initial_context=context)
        # Row j of the run is x̂_{j+1} with the context c_{j+1} made in the same step, which
        # the next step takes with it: the stretch starts at x̂_first, context c_first.
        start = first - 1
        out.append(
            Sequence(
                sensory=generated.sensory[start:],
                motor=generated.motor[start:],
                pattern=pattern,
                source=label,
                meta={"initial_context": generated.context[start], "pb": np.asarray(pb)},
            )
        )
    return out


def _check_new(
    model: TrainedModel, new_sequences: SequenceABC[Sequence], grow: bool = False
) -> None:
    if not new_sequences:
        raise DataFileError("no new sequences to add")
    net = model.network
    for seq in new_sequences:
        if seq.sensory.shape[1] != net.sensory_size or seq.motor.shape[1] != net.motor_size:
            raise ConfigError(
                f"{seq.source or 'a new sequence'}: has {seq.sensory.shape[1]} sensory and "
                f"{seq.motor.shape[1]} motor values per step but the model's network has "
                f"{net.sensory_size} and {net.motor_size}: a model of another network size"
            )
    clashes = sorted({s.pattern for s in new_sequences} & set(model.patterns))
    if clashes and not grow:
        raise ConfigError(
            f"new pattern name(s) {', '.join(repr(c) for c in clashes)} already learned by the "
            f"model (it holds {', '.join(model.patterns)}); a consolidation adds new patterns "
            "only: give the new one another name (its file name or `pattern` column)"
        )


def _original(
    model: TrainedModel, replay_data: SequenceABC[Sequence] | None, method: str
) -> list[Sequence]:
    """The stored original data, in the model's pattern order; it must hold exactly the
    model's patterns."""
    if not replay_data:
        raise ConfigError(
            f"method {method!r} needs the original training data of the model's "
            f"patterns ({', '.join(model.patterns)}); pass it (--replay-data)"
        )
    given = {s.pattern for s in replay_data}
    missing = [p for p in model.patterns if p not in given]
    extra = sorted(given - set(model.patterns))
    if missing or extra:
        raise ConfigError(
            "the original data must hold the model's patterns exactly: "
            + "; ".join(
                part
                for part in (
                    f"missing {', '.join(missing)}" if missing else "",
                    f"not learned by the model: {', '.join(extra)}" if extra else "",
                )
                if part
            )
        )
    order = {p: i for i, p in enumerate(model.patterns)}
    return sorted(replay_data, key=lambda s: order[s.pattern])  # stable: keeps the file order


def _replay_matches(
    model: TrainedModel, original: SequenceABC[Sequence], limits: np.ndarray
) -> bool:
    """Whether the original data are, bit for bit, those the model's history recorded
    (rounding when data are written to CSV can make them differ)."""
    for entry in model.history:
        if entry.added_data_fingerprint is not None:
            part = [s for s in original if s.pattern in entry.added]
            if not part or prepare_data(part, limits).fingerprint != entry.added_data_fingerprint:
                return False
    return True


def _held(
    config: ConsolidationConfig, learning: TrainConfig, n_old: int, n_new: int
) -> tuple[np.ndarray | None, int | None]:
    """The :class:`WarmStart`'s ``pb_held`` and ``hold_iterations`` for
    ``config.hold_old_pb``, the old sequences first."""
    if config.hold_old_pb == "off":
        return None, None
    held = np.concatenate([np.ones(n_old, dtype=bool), np.zeros(n_new, dtype=bool)])
    until = None if config.hold_old_pb == "all" else learning.iterations // 2
    return held, until


def consolidate(
    model: TrainedModel,
    new_sequences: SequenceABC[Sequence],
    config: ConsolidationConfig | None = None,
    *,
    replay_data: SequenceABC[Sequence] | None = None,
    parent: str | None = None,
    progress: bool | Callable[[TrainingProgress], None] = False,
    checkpoint_path: str | os.PathLike[str] | None = None,
    resume: bool = False,
    grow: bool = False,
) -> TrainedModel:
    """Add the patterns of ``new_sequences`` to ``model``; return the new model.

    A pattern is learned from all its sequences, as a first training learns each pattern
    from its demonstrations: give every performance of a new pattern. With ``grow`` a
    sequence may name a pattern the model holds: it is more data for that pattern (its PB and
    initial context start at the pattern's), learned with the pattern's rehearsal.

    Parameters
    ----------
    model : TrainedModel
        The learned model (not changed).
    new_sequences : list of Sequence
        Demonstrations of the new pattern(s): names the model does not hold (but with
        ``grow``), the model's sensory and motor sizes, values within its normalization.
    config : ConsolidationConfig
        The method and the learning (default: rehearsal with the model's own learning).
    replay_data : list of Sequence
        The original data of the model's patterns, for ``replay`` and ``scratch``.
    parent : str
        The model's file name, for the history.
    progress, checkpoint_path, resume
        As for :func:`rnnpb.model.training.train`: a checkpoint of a consolidation resumes only
        the same consolidation (same model, method, PB hold, data and learning).

    Returns
    -------
    TrainedModel
        The old sequences (rehearsed, replayed or, for finetune, as they were), then the new;
        ``meta["history"]`` is the model's history with this step appended.
    """
    _check_new(model, new_sequences, grow)
    config = (config or ConsolidationConfig()).resolved(model)
    learning = config.learning_for(model)
    limits = model_joint_limits(model)
    new = list(new_sequences)
    new_data = prepare_data(new, limits)  # checks the values lie within the normalization
    net = model.network
    if config.new_pb_start == "farthest":
        start_pb = farthest_pb(np.array(list(model.pattern_pb.values())))
        fresh_pb = np.tile(start_pb, (len(new), 1))
    else:
        fresh_pb = np.full((len(new), net.pb_size), 0.5)
    fresh_context = np.full((len(new), net.context_size), 0.5)
    grown = [i for i, s in enumerate(new) if s.pattern in model.patterns]
    for i in grown:  # more data of a learned pattern starts where that pattern is
        fresh_pb[i] = model.pattern_pb[new[i].pattern]
        fresh_context[i] = model.pattern_initial_context(new[i].pattern)
    details: dict[str, Any] = {}
    warm: WarmStart | None = None
    tag = f"{model.fingerprint}:{config.method}:new-pb={config.new_pb_start}"
    if config.method == "rehearsal":
        old = rehearse(
            model, config.rehearsal_steps, config.rehearsal_transient, config.rehearsal_source
        )
        warm = WarmStart(
            model.params,
            np.vstack([[s.meta["initial_context"] for s in old], fresh_context]),
            np.vstack([[s.meta["pb"] for s in old], fresh_pb]),
            tag,
            *_held(config, learning, len(old), len(new)),
            taught=(
                np.arange(len(old) + len(new)) < len(old)
                if config.rehearsal_target == "function"
                else None
            ),
        )
        details.update(
            rehearsal_steps=config.rehearsal_steps,
            rehearsal_transient=config.rehearsal_transient,
            rehearsal_source=config.rehearsal_source,
            rehearsal_target=config.rehearsal_target,
            hold_old_pb=config.hold_old_pb,
            new_pb_start=config.new_pb_start,
        )
        sequences = [*old, *new]
    elif config.method == "finetune":
        warm = WarmStart(model.params, fresh_context, fresh_pb, tag)
        sequences = new
    else:
        old = _original(model, replay_data, config.method)
        details["replay_data_matches_record"] = _replay_matches(model, old, limits)
        if config.method == "replay":
            pbs, contexts = (
                model.pattern_pb,
                {p: model.pattern_initial_context(p) for p in model.patterns},
            )
            warm = WarmStart(
                model.params,
                np.vstack([[contexts[s.pattern] for s in old], fresh_context]),
                np.vstack([[pbs[s.pattern] for s in old], fresh_pb]),
                tag,
                *_held(config, learning, len(old), len(new)),
            )
            details.update(hold_old_pb=config.hold_old_pb, new_pb_start=config.new_pb_start)
        sequences = [*old, *new]
    learned = train(
        sequences,
        limits,
        net,
        learning,
        progress=progress,
        checkpoint_path=checkpoint_path,
        resume=resume,
        warm_start=warm,
    )
    if warm is not None and warm.pb_held is not None and warm.hold_iterations is None:
        # A PB held to the end is the start's: its profile kept the float32 logit of it bit
        # for bit, and the round trip back is no learning.
        sequence_pb = learned.sequence_pb.copy()
        sequence_pb[warm.pb_held] = warm.pb[warm.pb_held]
        learned = replace(learned, sequence_pb=sequence_pb)
    if config.method == "finetune":
        # The old patterns were not trained: they keep their PBs and initial contexts.
        learned = replace(
            learned,
            sequence_pb=np.vstack([model.sequence_pb, learned.sequence_pb]),
            sequence_patterns=(*model.sequence_patterns, *learned.sequence_patterns),
            initial_context=np.vstack([model.initial_context, learned.initial_context]),
        )
    if config.method in ("rehearsal", "finetune"):
        # Replay and scratch learn from the original data, whose hands are the taught ones.
        learned = replace(learned, taught_sensory=_taught(model, learned, len(new)))
    training = learned.meta["training"]
    if grown:
        details["grown"] = sorted({new[i].pattern for i in grown})
    entry = HistoryEntry(
        method=config.method,
        added=tuple(dict.fromkeys(s.pattern for s in new)),
        patterns=learned.patterns,
        parent=Path(parent).name if parent else None,
        parent_fingerprint=model.fingerprint,
        train_config=learning.to_dict(),
        data_fingerprint=training["data_fingerprint"],
        added_data_fingerprint=new_data.fingerprint,
        iterations=int(training["iterations"]),
        seconds=float(training["seconds"]),
        created=datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        details=details,
    )
    # The new version plays at the step its data were taught at, and frames a person alike.
    kept = {k: model.meta[k] for k in ("dt", "framing_m") if model.meta.get(k) is not None}
    if kept:
        learned = replace(learned, meta={**learned.meta, **kept})
    return learned.with_history((*model.history, entry))
