"""The models a study starts from: the ones ``--models DIR`` names, else learned here.

``rnnpb demo`` writes a learning set's model as ``setK.npz`` and the larger set's as
``full.npz`` (or its first seed's ``full_seed0.npz``): :func:`study_models` reads those names
from a directory, and where no directory is given learns each model on the learning set's
draw of the demonstrator and saves it under the same name (or a study's own name for it), so
that a study runs on a fresh checkout. :func:`paper_training` is how the demo learns each set
(the full forms' models); the quick forms pass a short fast-preset learning of their own.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import replace
from pathlib import Path

from rnnpb.errors import ConfigError
from rnnpb.experiments.studies import demo_model_names
from rnnpb.model import TrainConfig


def paper_training(learning_set: str, seed: int = 0) -> TrainConfig:
    """How ``rnnpb demo`` learns ``learning_set``'s model with the paper's algorithm: its
    :class:`~rnnpb.experiments.jobs.ExperimentConfig`'s learning (the larger set's own)."""
    from rnnpb.experiments.jobs import ExperimentConfig

    demo = ExperimentConfig()
    return replace(demo.larger_train if learning_set == "full" else demo.train, seed=seed)


def learn_model(learning_set: str, train_config: TrainConfig, path: Path, data_seed: int) -> str:
    """Learn ``learning_set``'s model on the demonstrator's draw ``data_seed``; save it at
    ``path`` and return the path."""
    from rnnpb.demonstrator import learning_set as demonstrations
    from rnnpb.model import train
    from rnnpb.robot import JOINT_LIMITS

    model = train(demonstrations(learning_set, seed=data_seed), JOINT_LIMITS, config=train_config)
    model.save(path)
    return str(path)


def study_models(
    models: Iterable[str] | Mapping[str, str],
    directory: str | Path | None,
    out: Path,
    learning: Callable[[str], TrainConfig],
    data_seed: int = 0,
    pool=None,
    file_name: Callable[[str], str] | None = None,
    reuse: bool = False,
) -> dict[str, str]:
    """The path of each model: ``directory``'s (a clear error when it has none), or, with no
    directory, learned with ``learning(name)`` into ``out`` — in ``pool``'s worker processes
    when one is given (its ``submit``), else here.

    ``models``: learning sets (each model named by its set), or model names to their learning
    sets (a study that learns two models of one set). ``file_name(name)``: the learned model's
    file in ``out`` (None: the demo's, ``setK.npz``); ``reuse``: a model already at its file
    is taken, not learned again.
    """
    sets = dict(models) if isinstance(models, Mapping) else {name: name for name in models}
    if directory is not None:
        return {name: _found(Path(directory), set_name) for name, set_name in sets.items()}
    out.mkdir(parents=True, exist_ok=True)
    named = file_name or (lambda name: demo_model_names(sets[name])[0])
    paths = {name: out / named(name) for name in sets}
    jobs = {
        name: (learn_model, sets[name], learning(name), path, data_seed)
        for name, path in paths.items()
        if not (reuse and path.exists())
    }
    if pool is None:
        learned = {name: job[0](*job[1:]) for name, job in jobs.items()}
    else:
        futures = {name: pool.submit(*job) for name, job in jobs.items()}
        learned = {name: future.result() for name, future in futures.items()}
    return {name: learned.get(name, str(path)) for name, path in paths.items()}


def _found(directory: Path, learning_set: str) -> str:
    names = demo_model_names(learning_set)
    found = next((directory / n for n in names if (directory / n).is_file()), None)
    if found is None:
        raise ConfigError(
            f"{directory}: no model {' or '.join(names)} for learning set {learning_set} (the "
            "models `rnnpb demo` learns; run it, or give no --models to learn them here)"
        )
    return str(found)
