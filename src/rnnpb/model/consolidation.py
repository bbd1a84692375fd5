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
    predicts from the sequence's noisy inputs — rather than its own next steps
    (:data:`REHEARSAL_TARGET`);
``finetune``
    the new sequences alone: what interference looks like;
``replay``
    the new sequences and the stored original data (the caller passes it: the model file keeps
    only its fingerprint);
``scratch``
    the original data and the new sequences learned anew from random weights, with the
    model's own full learning: the upper bound.

All but ``scratch`` start from the model's weights ("warm start"); an old sequence starts from
its learned PB and initial context (by default held there for the first half), a new sequence
from context 0.5 and, by default, the PB farthest from the learned ones. The old patterns keep
their names, the new pattern gets PBs of its own, and the result records the step in its
history (:class:`rnnpb.model.io.HistoryEntry`).

Unlike the rest of the model this module reads a clock: the time the history records.
"""

from __future__ import annotations

import datetime
import os
from collections.abc import Callable
from collections.abc import Sequence as SequenceABC
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np

from rnnpb.errors import ConfigError, DataFileError
from rnnpb.model.generation import generate
from rnnpb.model.io import HistoryEntry, TrainedModel
from rnnpb.model.learning import TrainConfig, WarmStart, prepare_data
from rnnpb.model.training import TrainingProgress, train
from rnnpb.sequences import Sequence

CONSOLIDATION_METHODS = ("rehearsal", "finetune", "replay", "scratch")
"""The ways :func:`consolidate` adds patterns (see the module)."""
REHEARSAL_STEPS = 50
"""Steps of each rehearsed sequence: the length of the paper's demonstrations (2.2)."""
REHEARSAL_TRANSIENT = 200
"""Closed-loop steps run before a rehearsed sequence starts: the network falls onto the
pattern's limit cycle after a transient (paper 3.3), and what it rehearses is that cycle. With
100 steps what was rehearsed was partly still the transient, and the cycle the model generates
afterwards moved: learning set 1's pattern 1 by RMS 0.139-0.154 from the original model's; with
200 (the transient the study's generation measure discards) by 0.010-0.016 (docs/model.md,
"Consolidation")."""
# Iterations of a consolidation by each optimizer, when the caller names none. From warm
# weights, on learning set 1's model (the paper's algorithm) with its left-out pattern added by
# rehearsal, the mean training error fell from 3.1e-4 after 100 iterations to 4.4e-5 after
# 5,000 and only to 3.6e-5 after 20,000: a tenth of a first training's 50,000 iterations
# reaches the error. Rehearsing the old network's function (REHEARSAL_TARGET) needs more: what
# it learns is that function around each cycle, and with 5,000 iterations set 2's pattern 3
# moved by 0.065-0.070, with 20,000 by 0.047-0.053 (docs/model.md, "Consolidation"). 20,000
# take 17-19 s of one core, within the minute a consolidation may take. Adam (the fast preset)
# needs a tenth of its 3,000, rounded up.
CONSOLIDATION_ITERATIONS = {"momentum": 20_000, "adam": 500}
CONSOLIDATION_INPUT_NOISE = 0.01
"""The least noise (standard deviation, normalized units) on the teacher-forced inputs of a
warm-started consolidation when the caller names no learning (a rehearsal of the old
network's function takes :data:`FUNCTION_REHEARSAL_INPUT_NOISE`). Rehearsed sequences are exactly
what the network already generates, so without noise nothing in the learning holds an old
pattern's closed loop on its cycle while the weights move for the new one; with this much, on
the incremental study's measures from the demo's models (the paper's algorithm, no noise of
its own), the old cycles that stayed within RMS 0.05 of the original model's went from 20 to
23 of 24 on the two draws of the user and the new pattern's data where it was chosen (against
0.005, 0.015 and 0.02, with and without holding the old PBs), and from 19 to 23 of 24 on two
draws not looked at before, where the learning sets followed went from 6 to 7 of 8
(docs/model.md, "Consolidation"). A model learned with more noise (the fast preset's 0.02)
keeps its own."""
FUNCTION_REHEARSAL_INPUT_NOISE = 0.02
"""The least input noise of a rehearsal that learns the old network's function
(:data:`REHEARSAL_TARGET`): the noise is where that function is learned — the inputs near each
cycle a person's version of the pattern brings. With 20,000 iterations on the incremental
study's two draws, 0.02 followed 8 of 8 learning sets, 0.015 and 0.01 7 of 8 (docs/model.md,
"Consolidation")."""

HOLD_OLD_PB_OPTIONS = ("off", "all", "first-half")
"""How long a consolidation keeps the old sequences' PBs at their learned values:
never (they learn by eqs. 1–2 with the new ones), for all of it, or for its first half."""
HOLD_OLD_PB = "first-half"
"""The default: the old PBs stay for the first half, while the new pattern's error is largest,
and learn in the second. Together with a new PB that starts away from the old ones
(:data:`NEW_PB_START`) and the input noise, it followed 20 of 24 learning sets over six draws
of the user and the new pattern's data (the old PBs learning from the centre: 17) and kept 70
of 72 old cycles within RMS 0.05 (68); chosen on draws 0 and 1, checked on 4 and 5: 8 of 8 sets
against 4 (docs/model.md, "Consolidation")."""

NEW_PB_STARTS = ("centre", "farthest")
"""Where a new sequence's PB starts: at 0.5 like a first training's, or at the point of a grid
of PB space farthest from the learned patterns' PBs (:func:`farthest_pb`)."""
NEW_PB_START = "farthest"
"""The default: the new pattern starts where no old pattern is, so that learning it need not
push the old patterns' PBs aside (from the centre, with the old PBs held, the new pattern had
to grow out of the middle of them: docs/model.md, "Consolidation")."""

REHEARSAL_TARGETS = ("function", "trajectory")
"""What a rehearsed sequence learns towards: the old network's *function* — what the model,
from the pattern's PB and the stretch's context, predicts for the same noisy teacher-forced
inputs — or the rehearsed *trajectory*'s own next steps."""
REHEARSAL_TARGET = "function"
"""The default. A trajectory target teaches the network to pull every noisy input back onto
the rehearsed cycle: the cycle stays, but the network's response to hands near it (a person's
version of the pattern, which the original model learned) is lost, and its sensory prediction
error for the person rises towards the lock-on threshold (on learning set 4's model, pattern 1:
median 0.013 before, 0.020 after). The function target keeps that response, and with it
lock-on (docs/model.md, "Consolidation")."""

Method = Literal["rehearsal", "finetune", "replay", "scratch"]
HoldOldPB = Literal["off", "all", "first-half"]
NewPBStart = Literal["centre", "farthest"]
RehearsalTarget = Literal["function", "trajectory"]
RehearsalSource = Literal["patterns", "sequences"]
REHEARSAL_SOURCES = ("patterns", "sequences")
"""What :func:`rehearse` runs the closed loop from: each pattern's PB, or each sequence's."""
REHEARSAL_SOURCE: RehearsalSource = "patterns"
"""Rehearse from each pattern's PB: that is the PB generation and recognition use; a
pattern's sequences' own PBs can lie far apart, and their mean's cycle was not rehearsed (on
learning set 4's model, rehearsing each sequence's left pattern 1 locking on after 50 steps,
rehearsing the pattern's PB after 13)."""


@dataclass(frozen=True)
class ConsolidationConfig:
    """How to add patterns to a learned model.

    Attributes
    ----------
    method : str
        One of :data:`CONSOLIDATION_METHODS`.
    train : TrainConfig or None
        The learning. None: the model's own recorded learning (its optimizer, rates and seed)
        with :data:`CONSOLIDATION_ITERATIONS` iterations and at least
        :data:`CONSOLIDATION_INPUT_NOISE` on the inputs (a rehearsal of the old network's
        function: :data:`FUNCTION_REHEARSAL_INPUT_NOISE`) — for ``scratch`` the model's own
        full learning, unchanged.
    rehearsal_steps, rehearsal_transient : int
        Length of each rehearsed sequence, and the closed-loop steps run before it.
    rehearsal_source : str
        What :func:`rehearse` runs the closed loop from (:data:`REHEARSAL_SOURCES`).
    hold_old_pb : str
        One of :data:`HOLD_OLD_PB_OPTIONS`: whether the old sequences' PBs stay at their
        learned values while the weights learn the new pattern — ``"all"`` of the
        consolidation, its ``"first-half"`` (while the new pattern's error is largest), or
        ``"off"``. The new sequences' PBs always learn. For ``rehearsal`` and ``replay``, the
        methods that learn old sequences from their learned PBs; ``finetune`` learns no old
        sequence and ``scratch`` has no learned PB to hold, so neither uses it.
    new_pb_start : str
        One of :data:`NEW_PB_STARTS`: where the new sequences' PBs start (every warm-started
        method; ``scratch`` starts everything anew).
    rehearsal_target : str
        One of :data:`REHEARSAL_TARGETS`: what ``rehearsal``'s rehearsed sequences learn
        towards.
    """

    method: Method = "rehearsal"
    train: TrainConfig | None = None
    rehearsal_steps: int = REHEARSAL_STEPS
    rehearsal_transient: int = REHEARSAL_TRANSIENT
    rehearsal_source: RehearsalSource = REHEARSAL_SOURCE
    hold_old_pb: HoldOldPB = HOLD_OLD_PB
    new_pb_start: NewPBStart = NEW_PB_START
    rehearsal_target: RehearsalTarget = REHEARSAL_TARGET

    def __post_init__(self) -> None:
        if self.method not in CONSOLIDATION_METHODS:
            raise ConfigError(
                f"consolidation method must be one of "
                f"{', '.join(CONSOLIDATION_METHODS)}, got {self.method!r}"
            )
        if self.rehearsal_steps < 2:
            raise ConfigError(f"rehearsal_steps must be >= 2, got {self.rehearsal_steps}")
        if self.rehearsal_transient < 1:
            raise ConfigError(f"rehearsal_transient must be >= 1, got {self.rehearsal_transient}")
        if self.rehearsal_source not in REHEARSAL_SOURCES:
            raise ConfigError(
                f"rehearsal_source must be one of {', '.join(REHEARSAL_SOURCES)}, "
                f"got {self.rehearsal_source!r}"
            )
        if self.new_pb_start not in NEW_PB_STARTS:
            raise ConfigError(
                f"new_pb_start must be one of {', '.join(NEW_PB_STARTS)}, got {self.new_pb_start!r}"
            )
        if self.rehearsal_target not in REHEARSAL_TARGETS:
            raise ConfigError(
                f"rehearsal_target must be one of {', '.join(REHEARSAL_TARGETS)}, "
                f"got {self.rehearsal_target!r}"
            )
        if self.hold_old_pb not in HOLD_OLD_PB_OPTIONS:
            raise ConfigError(
                f"hold_old_pb must be one of {', '.join(HOLD_OLD_PB_OPTIONS)}, "
                f"got {self.hold_old_pb!r}"
            )

    def learning_for(self, model: TrainedModel) -> TrainConfig:
        """The :class:`TrainConfig` this consolidation of ``model`` learns with."""
        if self.train is not None:
            return self.train
        recorded = model.meta.get("train_config")
        try:
            own = (
                TrainConfig.from_dict(recorded)
                if isinstance(recorded, dict)
                else TrainConfig.paper()
            )
        except (TypeError, ValueError, KeyError) as error:
            raise ConfigError(
                f"the model's recorded training config is not usable ({error}); "
                "give the consolidation's learning explicitly"
            ) from None
        if self.method == "scratch":
            # The first training's length: a consolidated model records its consolidation's.
            first = model.history[0].train_config.get("iterations")
            return replace(own, iterations=first) if isinstance(first, int) else own
        least = (
            FUNCTION_REHEARSAL_INPUT_NOISE
            if self.method == "rehearsal" and self.rehearsal_target == "function"
            else CONSOLIDATION_INPUT_NOISE
        )
        return replace(
            own,
            iterations=CONSOLIDATION_ITERATIONS[own.optimizer],
            input_noise=max(own.input_noise, least),
        )


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
    n_steps: int = REHEARSAL_STEPS,
    transient: int = REHEARSAL_TRANSIENT,
    source: RehearsalSource = REHEARSAL_SOURCE,
) -> list[Sequence]:
    """Each learned pattern regenerated in closed loop, without the original data: one
    rehearsed sequence per learned sequence.

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


def _check_new(model: TrainedModel, new_sequences: SequenceABC[Sequence]) -> None:
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
    if clashes:
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
) -> TrainedModel:
    """Add the patterns of ``new_sequences`` to ``model``; return the new model.

    Parameters
    ----------
    model : TrainedModel
        The learned model (not changed).
    new_sequences : list of Sequence
        Demonstrations of the new pattern(s): names the model does not hold, the model's
        sensory and motor sizes, values within its normalization.
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
    config = config or ConsolidationConfig()
    _check_new(model, new_sequences)
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
    meta = {**learned.meta, "history": [e.to_json() for e in (*model.history, entry)]}
    return replace(learned, meta=meta)
