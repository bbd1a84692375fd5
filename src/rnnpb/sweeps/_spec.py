"""A sweep's grid, read from a small TOML file into frozen, validated settings.

::

    name = "scaling"                      # names the sweep in its table and report
    learning_sets = ["1", "2"]            # "1" … "4" (set K leaves pattern K out) or "full"
    seeds = 5                             # training seeds 0 … 4, or a list [0, 3, 7]
    user_draws = [100, 200]               # draws of the user's imperfection (scenario seeds)
    experiments = ["synchronization", "switching"]  # default: every one that applies

    [training.fast]                       # one table per training setting, by name
    preset = "fast"                       # "paper" (default) or "fast"
    iterations = 2000                     # any TrainConfig field; [training.fast.pb] for PB

    [online.default]                      # one table per on-line setting, by name
    preset = "default"                    # "default", "paper" or "ungated"; any OnlineConfig field

    studies = ["novelty", "safety"]       # any study of `rnnpb study`, once per seed
    quick = true                          # the studies' short form (default false)

A run is one point of the grid: learning set × training setting × seed × on-line setting ×
user draw, or study × seed (the seed is the study's ``StudyOptions.seed``). Every problem gets
one line naming the file and the key.
"""

from __future__ import annotations

import hashlib
import json
import tomllib
from dataclasses import asdict, dataclass, fields, is_dataclass, replace
from pathlib import Path
from typing import Any

from rnnpb.errors import ConfigError
from rnnpb.model import OnlineConfig, TrainConfig

LEARNING_SETS = ("1", "2", "3", "4", "full")
# What a run can measure; the larger set ("full") has no novel pattern, so it follows instead.
SET_EXPERIMENTS = ("synchronization", "switching", "attractors", "novel")
FULL_EXPERIMENTS = ("follows",)
EXPERIMENTS = (*SET_EXPERIMENTS, *FULL_EXPERIMENTS)
TRAIN_PRESETS = {"paper": TrainConfig.paper, "fast": TrainConfig.fast}
ONLINE_PRESETS = {
    "default": OnlineConfig,
    "paper": OnlineConfig.paper,
    "ungated": OnlineConfig.ungated,
}
TOP_KEYS = (
    "name",
    "learning_sets",
    "seeds",
    "user_draws",
    "experiments",
    "training",
    "online",
    "data_seed",
    "samples_per_pattern",
    "attractor_steps",
    "attractor_transient",
    "novel_amplitudes",
    "retries",
    "studies",
    "quick",
    "models",
)


@dataclass(frozen=True)
class Setting:
    """A named training or on-line setting of the grid."""

    name: str
    config: TrainConfig | OnlineConfig


@dataclass(frozen=True)
class RunSpec:
    """One run: the point of the grid and everything it needs (it pickles to a worker)."""

    sweep: str
    learning_set: str
    training: Setting
    seed: int
    online: Setting
    user_draw: int
    experiments: tuple[str, ...]
    data_seed: int
    samples_per_pattern: int
    attractor_steps: int
    attractor_transient: int
    novel_amplitudes: tuple[float, ...]

    @property
    def run_id(self) -> str:
        """A file-safe name, unique within the sweep."""
        return (
            f"set{self.learning_set}-{self.training.name}-seed{self.seed}-"
            f"{self.online.name}-draw{self.user_draw}"
        )

    @property
    def train_config(self) -> TrainConfig:
        assert isinstance(self.training.config, TrainConfig)
        return replace(self.training.config, seed=self.seed)

    @property
    def model_key(self) -> str:
        """The model cache's key: the learning data, the training config and the seed."""
        data = {
            "learning_set": self.learning_set,
            "data_seed": self.data_seed,
            "samples_per_pattern": self.samples_per_pattern,
            "train": asdict(self.train_config),
        }
        digest = hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()
        return f"set{self.learning_set}-{digest[:16]}"

    def grid_columns(self) -> dict[str, Any]:
        """The run's point of the grid, as the table's columns hold it."""
        return {
            "learning_set": self.learning_set,
            "training": self.training.name,
            "seed": self.seed,
            "online": self.online.name,
            "user_draw": self.user_draw,
            "study": "",
        }

    def config_json(self) -> str:
        """Everything that made this run's numbers, as one JSON string."""
        return json.dumps(
            {
                "learning_set": self.learning_set,
                "training": self.training.name,
                "train": asdict(self.train_config),
                "online_setting": self.online.name,
                "online": asdict(self.online.config),
                "seed": self.seed,
                "user_draw": self.user_draw,
                "experiments": list(self.experiments),
                "data_seed": self.data_seed,
                "samples_per_pattern": self.samples_per_pattern,
                "attractor_steps": self.attractor_steps,
                "attractor_transient": self.attractor_transient,
                "novel_amplitudes": list(self.novel_amplitudes),
            },
            sort_keys=True,
        )


@dataclass(frozen=True)
class StudyRunSpec:
    """One run of a study: ``rnnpb study STUDY [--quick]`` with ``StudyOptions.seed = seed``,
    one worker (the sweep runs several studies at once instead)."""

    sweep: str
    study: str
    seed: int
    quick: bool
    models: str | None = None  # StudyOptions.models: the learned models a study starts from

    @property
    def run_id(self) -> str:
        return f"study-{self.study}-seed{self.seed}{'-quick' if self.quick else ''}"

    @property
    def model_key(self) -> str:
        """A study learns or loads its own models: no run shares one with another."""
        return self.run_id

    def grid_columns(self) -> dict[str, Any]:
        return {
            "learning_set": "",
            "training": "",
            "seed": self.seed,
            "online": "",
            "user_draw": None,
            "study": self.study,
        }

    def config_json(self) -> str:
        return json.dumps(
            {
                "study": self.study,
                "seed": self.seed,
                "quick": self.quick,
                "workers": 1,
                "models": self.models,
            },
            sort_keys=True,
        )


AnyRun = RunSpec | StudyRunSpec


@dataclass(frozen=True)
class SweepSpec:
    """The grid of a sweep (see the module doc for the file)."""

    name: str
    learning_sets: tuple[str, ...]
    seeds: tuple[int, ...]
    user_draws: tuple[int, ...]
    training: tuple[Setting, ...]
    online: tuple[Setting, ...]
    experiments: tuple[str, ...] = ()  # empty: every experiment that applies to a set
    data_seed: int = 0
    samples_per_pattern: int = 2
    attractor_steps: int = 1000
    attractor_transient: int = 300
    novel_amplitudes: tuple[float, ...] = (1.0,)
    retries: int = 2  # how often a run whose worker died is tried again
    studies: tuple[str, ...] = ()  # studies of `rnnpb study`, each run once per seed
    quick: bool = False  # the studies' short form
    models: str | None = None  # the studies' StudyOptions.models (`rnnpb study --models`)

    def __post_init__(self) -> None:
        from rnnpb.experiments.studies import STUDY_MODULES

        if not self.learning_sets and not self.studies:
            raise ConfigError("the grid is empty: give 'learning_sets' or 'studies'")
        needs = ("seeds", "user_draws", "training", "online") if self.learning_sets else ("seeds",)
        for key in needs:
            if not getattr(self, key):
                raise ConfigError(f"the grid is empty: {key!r} has no values")
        for study in self.studies:
            if study not in STUDY_MODULES:
                raise ConfigError(f"study {study!r} is not one of {', '.join(STUDY_MODULES)}")
        if len(set(self.studies)) != len(self.studies):
            raise ConfigError(f"'studies' repeats a value: {list(self.studies)}")
        for name in self.learning_sets:
            if name not in LEARNING_SETS:
                raise ConfigError(f"learning set {name!r} is not one of {', '.join(LEARNING_SETS)}")
        for experiment in self.experiments:
            if experiment not in EXPERIMENTS:
                raise ConfigError(
                    f"experiment {experiment!r} is not one of {', '.join(EXPERIMENTS)}"
                )
        for key in ("seeds", "user_draws", "learning_sets"):
            values = getattr(self, key)
            if len(set(values)) != len(values):
                raise ConfigError(f"{key!r} repeats a value: {list(values)}")
        for key in ("training", "online"):
            names = [s.name for s in getattr(self, key)]
            if len(set(names)) != len(names):
                raise ConfigError(f"{key!r} repeats a setting name: {names}")
        if any(s < 0 for s in self.seeds):
            raise ConfigError(f"seeds must be >= 0, got {list(self.seeds)}")
        if self.retries < 0:
            raise ConfigError(f"retries must be >= 0, got {self.retries}")
        if not 0 <= self.attractor_transient < self.attractor_steps:
            raise ConfigError("attractor_transient must lie in [0, attractor_steps)")
        if self.samples_per_pattern < 1:
            raise ConfigError("samples_per_pattern must be >= 1")

    def experiments_for(self, learning_set: str) -> tuple[str, ...]:
        applies = FULL_EXPERIMENTS if learning_set == "full" else SET_EXPERIMENTS
        if not self.experiments:
            return applies
        return tuple(e for e in self.experiments if e in applies)

    def runs(self) -> list[AnyRun]:
        """Every point of the grid, in a fixed order: the learning sets' runs, then the
        studies'."""
        studies: list[AnyRun] = [
            StudyRunSpec(self.name, study, seed, self.quick, self.models)
            for study in self.studies
            for seed in self.seeds
        ]
        return [
            RunSpec(
                self.name,
                learning_set,
                training,
                seed,
                online,
                draw,
                self.experiments_for(learning_set),
                self.data_seed,
                self.samples_per_pattern,
                self.attractor_steps,
                self.attractor_transient,
                self.novel_amplitudes,
            )
            for learning_set in self.learning_sets
            for training in self.training
            for seed in self.seeds
            for online in self.online
            for draw in self.user_draws
        ] + studies


def _with_changes(config: Any, changes: dict[str, Any], where: str) -> Any:
    """``config`` with the fields in ``changes`` replaced (nested dataclasses by table)."""
    known = {f.name: f for f in fields(config)}
    updates: dict[str, Any] = {}
    for key, value in changes.items():
        if key not in known:
            raise ConfigError(f"{where}: unknown key {key!r} (known: {', '.join(known)})")
        current = getattr(config, key)
        if is_dataclass(current):
            if not isinstance(value, dict):
                raise ConfigError(f"{where}.{key} must be a table")
            updates[key] = _with_changes(current, value, f"{where}.{key}")
        elif isinstance(value, dict):
            raise ConfigError(f"{where}.{key} must be a value, not a table")
        else:
            updates[key] = tuple(value) if isinstance(value, list) else value
    # A tuned value (read from the learning preset, not a constructor's setting) changes by
    # the config's with_tuning.
    tuned = {k: v for k, v in updates.items() if not known[k].init}
    settings = {k: v for k, v in updates.items() if known[k].init}
    try:
        changed = config.with_tuning(**tuned) if tuned else config
        return replace(changed, **settings)
    except TypeError as error:
        raise ConfigError(f"{where}: {error}") from None


def _settings(table: Any, key: str, presets: dict[str, Any], default: str) -> tuple[Setting, ...]:
    if not isinstance(table, dict):
        raise ConfigError(f"{key!r} must be a table of named settings ([{key}.NAME])")
    out = []
    for name, body in table.items():
        if not isinstance(body, dict):
            raise ConfigError(f"[{key}.{name}] must be a table")
        body = dict(body)
        preset = body.pop("preset", default)
        if preset not in presets:
            raise ConfigError(
                f"[{key}.{name}] preset {preset!r} is not one of {', '.join(presets)}"
            )
        out.append(Setting(str(name), _with_changes(presets[preset](), body, f"[{key}.{name}]")))
    return tuple(out)


def _ints(value: Any, key: str) -> tuple[int, ...]:
    if isinstance(value, int) and not isinstance(value, bool):
        return tuple(range(value))
    if isinstance(value, list) and all(
        isinstance(v, int) and not isinstance(v, bool) for v in value
    ):
        return tuple(value)
    raise ConfigError(f"{key!r} must be a count or a list of whole numbers, got {value!r}")


def parse_spec(data: dict[str, Any], default_name: str = "sweep") -> SweepSpec:
    """A :class:`SweepSpec` from a parsed TOML document."""
    unknown = [k for k in data if k not in TOP_KEYS]
    if unknown:
        raise ConfigError(f"unknown key {unknown[0]!r} (known: {', '.join(TOP_KEYS)})")
    sets = data.get("learning_sets", [])
    if not isinstance(sets, list):
        raise ConfigError("'learning_sets' must be a list")
    studies = data.get("studies", [])
    if not isinstance(studies, list):
        raise ConfigError("'studies' must be a list")
    quick = data.get("quick", False)
    if not isinstance(quick, bool):
        raise ConfigError(f"'quick' must be true or false, got {quick!r}")
    models = data.get("models")
    if models is not None and not isinstance(models, str):
        raise ConfigError(f"'models' must be a folder name, got {models!r}")
    if models is not None and not studies:
        raise ConfigError("'models' applies to studies, and the spec has none")
    if studies and not sets:
        for key in ("training", "online", "experiments", "user_draws", "novel_amplitudes"):
            if key in data:
                raise ConfigError(f"{key!r} applies to learning sets, and the spec has none")
    experiments = data.get("experiments", [])
    if not isinstance(experiments, list):
        raise ConfigError("'experiments' must be a list")
    amplitudes = data.get("novel_amplitudes", [1.0])
    if not isinstance(amplitudes, list) or not all(isinstance(a, (int, float)) for a in amplitudes):
        raise ConfigError("'novel_amplitudes' must be a list of numbers")
    options = {
        k: data[k]
        for k in (
            "data_seed",
            "samples_per_pattern",
            "attractor_steps",
            "attractor_transient",
            "retries",
        )
        if k in data
    }
    for key, value in options.items():
        if not isinstance(value, int) or isinstance(value, bool):
            raise ConfigError(f"{key!r} must be a whole number, got {value!r}")
    return SweepSpec(
        name=str(data.get("name", default_name)),
        learning_sets=tuple(str(s) for s in sets),
        seeds=_ints(data.get("seeds", []), "seeds"),
        user_draws=_ints(data.get("user_draws", [100]), "user_draws"),
        training=_settings(data.get("training", {}), "training", TRAIN_PRESETS, "paper"),
        online=_settings(data.get("online", {"default": {}}), "online", ONLINE_PRESETS, "default"),
        experiments=tuple(str(e) for e in experiments),
        novel_amplitudes=tuple(float(a) for a in amplitudes),
        studies=tuple(str(s) for s in studies),
        quick=quick,
        models=models,
        **options,
    )


def load_spec(path: str | Path) -> SweepSpec:
    """Read a sweep spec; any problem is one :class:`ConfigError` line naming the file."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ConfigError(f"sweep spec {path}: no such file") from None
    except (OSError, UnicodeDecodeError) as error:
        raise ConfigError(f"sweep spec {path}: cannot read it ({error})") from None
    except tomllib.TOMLDecodeError as error:
        raise ConfigError(f"sweep spec {path}: not TOML ({error})") from None
    try:
        return parse_spec(data, default_name=path.stem)
    except ConfigError as error:
        raise ConfigError(f"sweep spec {path}: {error}") from None
