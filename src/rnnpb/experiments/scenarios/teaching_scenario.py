"""The teach study's scenario: the scripted user, the study's settings and its starting models.

Per learning set and new movement — each of the demonstrator's new shapes
(:data:`rnnpb.demonstrator.NEW_SHAPES`) and each free shape
(:mod:`rnnpb.experiments.scenarios.free_shapes`: shapes the demonstrator does not make) — a
scripted user shows the robot the movement as a person shows something (:func:`segments`): a
learned pattern; the movement for ``showing_cycles`` cycles (its first showing); another learned
pattern; a random walk; the movement again (its second showing); the other learned patterns;
jerky movement and a random walk; and the movement a third time, for ``third_cycles`` cycles.
The robot should keep both showings, learn the movement from them before the third begins,
recognise the third, and keep nothing of the random movement. Every run is made at each step
time of the study: the same movements in steps, so that at 0.1 s a person moves four times
faster (the demonstrator's 12-step cycle is 1.2 s, a person's own tempo).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from rnnpb.errors import ConfigError
from rnnpb.experiments.scenarios.study_models import paper_training, study_models
from rnnpb.interaction.teaching import TeachingConfig
from rnnpb.model import OnlineConfig

UNSTRUCTURED_MOVEMENTS = ("random-walk", "jerky")
PERIOD = 12  # the demonstrator's period, steps (PatternConfig.period_steps)
FREE = "free-"  # a free shape's name: free-SEED


@dataclass(frozen=True)
class TeachConfig:
    """What the study runs.

    ``models``: the directory of the starting models (:func:`starting_models`; None: learned
    with the paper's algorithm); ``shipped``: teach the shipped fast-preset model of learning
    set 1 instead (the quick form). ``consolidation_iterations``: None keeps
    teaching's policy (the model's preset's ``[teaching]`` ``iterations``:
    :func:`rnnpb.model.consolidation.consolidation_config` with ``purpose="teach"``), so that
    what improves there is what this study measures. The scripted user: ``lead_steps``
    shows (:func:`segments`): ``showing_cycles`` cycles of each of the first two showings,
    ``third_cycles`` of the third, ``other_cycles`` of each learned pattern, ``unstructured_steps``
    of each unstructured movement. ``paced``: the (learning set, shape) whose kept episodes are
    consolidated again during a paced run at each step time; ``paced_max_steps`` ends that run
    early (the consolidation is then cancelled: the quick form), else it ends
    ``paced_after_swap`` steps after the swap. ``training_seed``: the starting models'
    demonstrations and weights.
    """

    quick: bool = False
    models: str | None = None
    shipped: bool = False
    learning_sets: tuple[str, ...] = ("1", "2", "3", "4", "full")
    shapes: tuple[str, ...] = ("figure-eight", "diagonal", "one-arm", "asymmetric")
    free_shapes: tuple[int, ...] = (700, 701, 702, 703)
    step_times: tuple[float, ...] = (0.4, 0.1)
    online: OnlineConfig = field(default_factory=OnlineConfig)
    teaching: TeachingConfig = field(default_factory=TeachingConfig)
    consolidation_iterations: int | None = None
    dt: float = 0.4
    showing_cycles: int = 3
    third_cycles: int = 4
    other_cycles: int = 3
    unstructured_steps: int = 36
    scenario_seed: int = 600
    training_seed: int = 0
    # The paper's measures after learning: the demo's 75 steps before the pause; switching is
    # judged within 15 steps, so 30 of each pattern (the demo's 50) still show "never".
    sync_before: int = 75
    switch_steps_each: int = 30
    switching_pairs: str = "all"  # "all", or "new": the pairs with the new pattern only
    # The paper's measures before and after teaching (the quick form judges the old patterns
    # by their lock-on in the timeline only).
    paper_measures: bool = False
    paced: tuple[str, str] | None = ("1", "figure-eight")
    paced_max_steps: int | None = None
    paced_after_swap: int = 36
    workers: int = 2

    def __post_init__(self) -> None:
        from rnnpb.demonstrator import NEW_SHAPES, learning_set_patterns

        for name in self.learning_sets:
            learning_set_patterns(name)
        unknown = [s for s in self.shapes if s not in NEW_SHAPES]
        if unknown or not self.shapes or not self.learning_sets:
            raise ConfigError(
                f"the study teaches new shapes of the demonstrator ({', '.join(NEW_SHAPES)}) "
                f"to one or more learning sets; got shapes {self.shapes}"
            )
        if self.switching_pairs not in ("all", "new"):
            raise ConfigError(f"switching_pairs must be 'all' or 'new', got {self.switching_pairs}")
        if min(self.showing_cycles, self.third_cycles, self.other_cycles) < 1:
            raise ConfigError("a showing and a learned pattern need at least one cycle each")
        if not self.step_times or any(not dt > 0 for dt in self.step_times):
            raise ConfigError(f"step times must be > 0 s, got {self.step_times}")

    @property
    def movements(self) -> tuple[str, ...]:
        """Every new movement taught: the demonstrator's shapes, then the free shapes."""
        return (*self.shapes, *(f"{FREE}{seed}" for seed in self.free_shapes))

    @classmethod
    def quick_run(cls, seed: int = 0) -> TeachConfig:
        """The shipped model of learning set 1, one shape, at the paper's step; the paced run
        stops (and cancels its consolidation) after 8 steps."""
        return cls(
            quick=True,
            models=None,
            shipped=True,
            learning_sets=("1",),
            shapes=("figure-eight",),
            free_shapes=(),
            step_times=(0.4,),
            online=OnlineConfig.ungated(),
            scenario_seed=600 + seed,
            sync_before=36,
            switch_steps_each=30,
            switching_pairs="new",
            paper_measures=False,
            paced_max_steps=8,
            workers=1,
        )


def period_of(movement: str) -> int:
    """Steps per cycle of a movement the scripted user performs."""
    if movement.startswith(FREE):
        from rnnpb.experiments.scenarios.free_shapes import free_shape

        return free_shape(int(movement[len(FREE) :])).period
    return PERIOD


def segments(
    patterns: tuple[str, ...], shape: str, index: int, config: TeachConfig
) -> list[tuple[str, int]]:
    """What the user performs, (movement, steps) in order, when taught the ``index``-th shape
    (the module doc): the learned pattern it leads with is another per shape."""
    lead = patterns[index % len(patterns)]
    others = [p for p in patterns if p != lead]
    showing = config.showing_cycles * period_of(shape)
    other = config.other_cycles * PERIOD
    walk, jerky = UNSTRUCTURED_MOVEMENTS
    return [
        (lead, other),
        (shape, showing),
        (others[0], other),
        (walk, config.unstructured_steps),
        (shape, showing),
        *((p, other) for p in others[1:]),
        (jerky, config.unstructured_steps),
        (walk, config.unstructured_steps),
        (shape, config.third_cycles * period_of(shape)),
    ]


def showing_stream(performed: list[tuple[str, int]], seed: int, dt: float):
    """The user's performance of ``performed`` as a :class:`rnnpb.demonstrator.Scenario` at
    ``dt``: the demonstrator's movements as it performs them, the free shapes as a person would
    (:func:`~rnnpb.experiments.scenarios.free_shapes.perform_free`), each blending into the next
    over two steps."""
    import numpy as np

    from rnnpb.demonstrator import MirrorMapping, PatternConfig, Scenario, perform
    from rnnpb.experiments.scenarios.free_shapes import free_shape, perform_free
    from rnnpb.robot.camera import RobotCamera

    config = PatternConfig(dt=dt)
    rng = np.random.default_rng(seed)
    hands, measured, labels, phase = [], [], [], []
    for movement, steps in performed:
        if movement.startswith(FREE):
            shape_hands, shape_phase = perform_free(
                free_shape(int(movement[len(FREE) :])), steps, rng
            )
            shape_measured = shape_hands + config.imperfection.sensor_noise * rng.standard_normal(
                shape_hands.shape
            )
        else:
            motion = perform([(movement, steps)], config, rng)
            shape_hands, shape_measured, shape_phase = motion.hands, motion.measured, motion.phase
        if hands:
            last = hands[-1][-1]
            for k in range(min(2, steps)):
                w = (k + 1) / 3
                shape_hands[k] = (1 - w) * last + w * shape_hands[k]
                shape_measured[k] = (1 - w) * measured[-1][-1] + w * shape_measured[k]
        hands.append(shape_hands)
        measured.append(shape_measured)
        phase.append(shape_phase)
        labels += [movement] * steps
    all_hands = np.concatenate(hands)
    switches = tuple(t for t in range(1, len(labels)) if labels[t] != labels[t - 1])
    return Scenario(
        name=source_spec(performed),
        hands=all_hands,
        sensory=RobotCamera().sensory_from_hands(np.concatenate(measured)),
        motor=MirrorMapping(config.body, dt=dt).motor_from_hands(all_hands),
        labels=tuple(labels),
        switch_steps=switches,
        novel=(),
        phase=np.concatenate(phase),
        dt=dt,
    )


def source_spec(segments: list[tuple[str, int]]) -> str:
    """The segments as a ``--source`` specification (what the memory records as the source)."""
    return "scenario:steps:" + ",".join(f"{m}*{n}" for m, n in segments)


def starting_models(config: TeachConfig, out: Path, pool=None) -> dict[str, str]:
    """The path of each learning set's starting model at ``config.dt``: the shipped one,
    ``config.models``'s, or learned into ``out`` with the paper's algorithm as ``rnnpb demo``
    learns it, from the demonstrator's draw ``config.training_seed`` (in ``pool``'s workers
    when one is given). A model learned at another step than ``config.dt`` is the same network
    at this one: the demonstrator's movements are the same in steps, and within the servos'
    speed at 0.1 s (the learning phase's check, at ``config.dt``, says so or refuses)."""
    if config.shipped:
        from rnnpb.models import SHIPPED_MODEL

        paths = {"1": str(SHIPPED_MODEL)}
    else:
        paths = study_models(
            config.learning_sets,
            config.models,
            out,
            lambda name: paper_training(name, config.training_seed),
            data_seed=config.training_seed,
            pool=pool,
        )
    return {name: _at_step(name, path, config, out) for name, path in paths.items()}


def _at_step(name: str, path: str, config: TeachConfig, out: Path) -> str:
    """The model at ``path`` playing at ``config.dt``: itself, or a copy in ``out`` that plays
    at that step after the check of its learning data at it."""
    from dataclasses import replace

    from rnnpb.demonstrator import learning_set
    from rnnpb.model import TrainedModel
    from rnnpb.safety import check_data

    model = TrainedModel.load(path)
    if abs(model.dt - config.dt) < 1e-9:
        return path
    safety = check_data(learning_set(name, seed=config.training_seed), dt=config.dt)
    if safety.unsafe:
        raise ConfigError(
            f"learning set {name} cannot be learned at dt {config.dt}: {safety.first}"
        )
    out.mkdir(parents=True, exist_ok=True)
    copy = out / f"{Path(path).stem}_dt{config.dt:g}.npz"
    replace(model, meta={**model.meta, "dt": config.dt}).save(copy)
    return str(copy)
