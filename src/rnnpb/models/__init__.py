"""Models shipped with the package, so that a fresh install has something to interact with.

``set1_fast.npz``: learning set 1 (patterns 1, 2 and 3) learned with the fast preset, seed 0,
by ``scripts/train_shipped_model.py`` (which says how to learn it again). Where the commands
look for a model when none is given: :func:`default_model_locations`.
"""

from __future__ import annotations

from pathlib import Path

SHIPPED_MODEL: Path = Path(__file__).resolve().parent / "set1_fast.npz"

#: Where a model is looked for, in order, when a command is given none: a `models/` folder of
#: the user's own, then what `make demo` (``rnnpb demo``) writes.
SEARCHED_FOLDERS: tuple[str, ...] = ("models", "results/demo/models")


def default_model_locations(base: Path | None = None) -> list[Path]:
    """The model folders that exist under ``base`` (default: the working directory), in the
    order of :data:`SEARCHED_FOLDERS`, then the shipped model."""
    base = Path.cwd() if base is None else Path(base)
    found = [
        base / name
        for name in SEARCHED_FOLDERS
        if (base / name).is_dir() and any(_models_in(base / name))
    ]
    return [*found, SHIPPED_MODEL]


def default_model(base: Path | None = None) -> Path:
    """The first place a command looks for a model when given none (see
    :func:`default_model_locations`): a folder of models, or the shipped model."""
    return default_model_locations(base)[0]


def first_model_file(location: Path) -> Path:
    """``location`` itself when it is a file, else the first model file in the folder by name
    (``set1.npz`` before ``set2.npz``); checkpoints are no models."""
    location = Path(location)
    if not location.is_dir():
        return location
    files = sorted(_models_in(location))
    return files[0] if files else location


def _models_in(folder: Path):
    return (p for p in folder.glob("*.npz") if not p.name.endswith(".checkpoint.npz"))


__all__ = [
    "SEARCHED_FOLDERS",
    "SHIPPED_MODEL",
    "default_model",
    "default_model_locations",
    "first_model_file",
]
