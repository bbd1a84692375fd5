"""A value from a preset file or a ``--config`` file reaches the code that computes with it
through at most four files (docs/design.md, "Settings: from a file to the code that uses it").

A **hop** is a file of rnnpb whose code hands on, receives or returns the value itself or a
plain table that holds it (a dict or mapping, a list or tuple, nested up to four deep), from
the TOML text to the config the computing code is given, plus the file of that code. A config
object, a preset or a ``--config`` file's object passed along unchanged is no hop: the file
that reads the value out of it is.

The route is measured, not declared: each road runs as the command runs it, with a value no
preset holds in its place, under a profiler that marks every file in which a call hands on,
receives or returns the value or a table that holds it (a call into the standard library or a
dataclass's constructor marks the file that called it). Each road stops where the config is
made, and asserts that the value arrived.
"""

from __future__ import annotations

import re
import sys
import threading
from collections.abc import Callable, Mapping
from pathlib import Path
from types import MappingProxyType
from typing import Any

import pytest

import rnnpb
from rnnpb.cli import main
from rnnpb.models import SHIPPED_MODEL

ROOT = Path(rnnpb.__file__).parent
MOST_HOPS = 4

# (section, key) -> the value put in its place (no preset holds it) and the file whose code
# computes with it.
VALUES: dict[tuple[str, str], tuple[float, str]] = {
    ("online", "surprise_gate"): (0.0123457, "model/online.py"),
    ("online.pb", "learning_rate"): (0.345679, "model/parametric_bias.py"),
    ("recognition", "switch_steps"): (77777, "model/recognition.py"),
    ("teaching.cutter", "episode_cycles"): (55555, "interaction/episodes.py"),
    ("teaching", "iterations"): (33333, "model/training.py"),
    ("consolidation", "iterations"): (44444, "model/training.py"),
}


class Arrived(Exception):
    """The road reached the config the computing code is given."""


def _holds(value: Any, marker: float, depth: int = 0) -> bool:
    if isinstance(value, bool):
        return False
    if isinstance(value, int | float):
        return value == marker
    if depth >= 4:
        return False
    if isinstance(value, dict | MappingProxyType) or (
        isinstance(value, Mapping) and type(value).__module__.startswith("rnnpb")
    ):
        try:
            items = list(value.values())
        except Exception:  # noqa: BLE001 - a mapping half made (its __init__ being called)
            return False
    elif isinstance(value, list | tuple | set | frozenset):
        items = value
    else:
        return False
    return len(items) <= 256 and any(_holds(v, marker, depth + 1) for v in items)


def _file(frame) -> str | None:
    """The rnnpb file of ``frame``, or of the nearest rnnpb frame that called it."""
    while frame is not None:
        name = frame.f_code.co_filename
        if name.startswith(str(ROOT)):
            return Path(name).relative_to(ROOT).as_posix()
        frame = frame.f_back
    return None


class Route:
    """The files of rnnpb that hand on, receive or return ``marker`` (or a table holding it)
    while the block runs."""

    def __init__(self, marker: float) -> None:
        self.marker = marker
        self.files: set[str] = set()

    def _profile(self, frame, event: str, arg: Any) -> None:
        if event == "call":
            values = list(frame.f_locals.values())  # the arguments
        elif event == "return":
            values = [arg]
        else:
            return
        near = _file(frame)
        if near is None or not any(_holds(v, self.marker) for v in values):
            return
        # the callee (or, for a library's code, the rnnpb file that called it) and its caller
        self.files.add(near)
        caller = _file(frame.f_back)
        if caller is not None:
            self.files.add(caller)

    def __enter__(self) -> Route:
        threading.setprofile(self._profile)
        sys.setprofile(self._profile)
        return self

    def __exit__(self, *exc: object) -> None:
        sys.setprofile(None)
        threading.setprofile(None)


def _config_file(folder: Path, keys: list[tuple[str, str]]) -> Path:
    path = folder / "research.toml"
    path.write_text("".join(f"[{s}]\n{k} = {VALUES[s, k][0]}\n" for s, k in keys))
    return path


@pytest.fixture()
def marked_presets(monkeypatch):
    """The shipped presets with each value of :data:`VALUES` replaced by its marker."""
    from rnnpb import presets
    from rnnpb.interaction import episodes
    from rnnpb.model import learning, online_config, recognition

    caches = [
        presets.load_preset,
        online_config._default_tuning,
        online_config._paper_online,
        online_config._ungated,
        recognition._preset_tuning,
        recognition._preset_config,
        learning._preset_tuning,
    ]
    files = presets.resources.files

    def marked(text: str) -> str:
        for (section, key), (marker, _) in VALUES.items():
            start = text.index(f"\n[{section}]\n") + len(section) + 4
            end = text.find("\n[", start)
            block = re.sub(rf"^{key} = .*$", f"{key} = {marker}", text[start:end], flags=re.M)
            text = text[:start] + block + text[end:]
        return text

    class Package:
        def __init__(self, name: str) -> None:
            self.files = files(name)

        def joinpath(self, name: str):
            found = self.files.joinpath(name)
            preset = name in ("paper.toml", "fast.toml")

            class File:
                def read_text(self, *args: Any, **kwargs: Any) -> str:
                    text = found.read_text(*args, **kwargs)
                    return marked(text) if preset else text

            return File()

        def __truediv__(self, name: str):
            return self.files / name

        def __getattr__(self, name: str) -> Any:
            return getattr(self.files, name)

    for cache in caches:
        cache.cache_clear()
    monkeypatch.setattr(presets.resources, "files", Package)
    assert (
        episodes.TeachingConfig().episode_cycles == VALUES["teaching.cutter", "episode_cycles"][0]
    )
    yield
    monkeypatch.undo()
    for cache in caches:
        cache.cache_clear()


def _interact(tmp_path: Path, config: Path | None, learn: bool, monkeypatch) -> dict[str, Any]:
    """``rnnpb interact`` up to the mirror system (or, with ``--learn``, up to the teacher's
    first consolidation, handed to its process): what it was given."""
    import rnnpb.interaction.background as background
    import rnnpb.interaction.teaching as teaching
    import rnnpb.model

    given: dict[str, Any] = {}

    def mirror(model, config, recognition=None, **options):
        given.update(online=config, recognition=recognition)
        raise Arrived

    class Teacher(teaching.Teacher):
        def __init__(self, *args: Any, **kwargs: Any) -> None:
            super().__init__(*args, **kwargs)
            given["cutter"] = self.keeper.cutter.config
            given["consolidation"] = self.consolidation(
                rnnpb.model.TrainedModel.load(SHIPPED_MODEL)
            )
            self.pending = [1]
            self.confirm()  # the consolidation's process, given its arguments
            raise Arrived

    class Started:
        def __init__(self, target: Callable, daemon: bool, args: tuple) -> None:
            given["process"] = args

        def start(self) -> None:
            pass

    real = background.process_context()

    class Context:
        Process = Started

        def Queue(self):  # noqa: N802 - the multiprocessing context's name
            return None

        def get_start_method(self) -> str:
            return real.get_start_method()

    if learn:
        monkeypatch.setattr(teaching, "Teacher", Teacher)
        monkeypatch.setattr(background, "process_context", Context)
    else:
        monkeypatch.setattr(rnnpb.model, "MirrorSystem", mirror)
    args = ["interact", "--model", str(SHIPPED_MODEL), "--source", "scenario:held:1"]
    args += ["--out", str(tmp_path / "run"), "--steps", "2", "--no-progress"]
    args += ["--learn"] if learn else []
    args += ["--config", str(config)] if config is not None else []
    with pytest.raises(Arrived):
        main(args)
    return given


def _consolidate(tmp_path: Path, config: Path | None, monkeypatch) -> dict[str, Any]:
    """``rnnpb consolidate`` up to the consolidation: what it was given."""
    import rnnpb.model.consolidation as consolidation
    from rnnpb.demonstrator import pattern_dataset
    from rnnpb.sequences import write_sequence

    given: dict[str, Any] = {}

    def consolidate(model, new, config, **kwargs):
        given["consolidation"] = config
        raise Arrived

    monkeypatch.setattr(consolidation, "consolidate", consolidate)
    (sequence, *_) = pattern_dataset(patterns=("figure-eight",), samples_per_pattern=1)
    write_sequence(tmp_path / "new" / "pnew_1.csv", sequence)
    args = ["consolidate", "--model", str(SHIPPED_MODEL), "--add", str(tmp_path / "new")]
    args += ["--out", str(tmp_path / "m2.npz"), "--no-progress"]
    args += ["--config", str(config)] if config is not None else []
    with pytest.raises(Arrived):
        main(args)
    return given


def _hops(road: Callable[[], dict[str, Any]], key: tuple[str, str], arrived) -> list[str]:
    marker, user = VALUES[key]
    with Route(marker) as route:
        given = road()
    assert arrived(given) == marker, f"{key} did not arrive"
    assert key[1] in (ROOT / user).read_text(), f"{user} does not compute with {key[1]}"
    return sorted(route.files | {user})


ARRIVED = {
    ("online", "surprise_gate"): lambda given: given["online"].surprise_gate,
    ("online.pb", "learning_rate"): lambda given: given["online"].pb.learning_rate,
    ("recognition", "switch_steps"): lambda given: given["recognition"].switch_steps,
    ("teaching.cutter", "episode_cycles"): lambda given: given["cutter"].episode_cycles,
    ("teaching", "iterations"): lambda given: given["consolidation"].train.iterations,
    ("consolidation", "iterations"): lambda given: given["consolidation"].train.iterations,
}
ROADS = {
    "interact": [
        ("online", "surprise_gate"),
        ("online.pb", "learning_rate"),
        ("recognition", "switch_steps"),
    ],
    "interact --learn": [("teaching.cutter", "episode_cycles"), ("teaching", "iterations")],
    "consolidate": [("consolidation", "iterations")],
}


@pytest.mark.parametrize(
    ("road", "key"),
    [(road, key) for road, keys in ROADS.items() for key in keys],
    ids=lambda item: item if isinstance(item, str) else ".".join(item),
)
@pytest.mark.parametrize("origin", ["preset", "config"])
def test_a_value_reaches_its_use_in_few_hops(road, key, origin, tmp_path, monkeypatch, request):
    if origin == "preset":
        request.getfixturevalue("marked_presets")
    config = _config_file(tmp_path, [key]) if origin == "config" else None
    runs = {
        "interact": lambda: _interact(tmp_path, config, False, monkeypatch),
        "interact --learn": lambda: _interact(tmp_path, config, True, monkeypatch),
        "consolidate": lambda: _consolidate(tmp_path, config, monkeypatch),
    }
    hops = _hops(runs[road], key, ARRIVED[key])
    assert len(hops) <= MOST_HOPS, f"[{key[0]}] {key[1]} from the {origin} by {road}: {hops}"
