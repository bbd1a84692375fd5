"""The layout of docs/design.md, held to the code: every import inside rnnpb points down.

Each part (a subpackage or a top-level module of rnnpb) may import only the parts listed for it
in ALLOWED. A part that is not listed fails the test until docs/design.md and this table say
where it stands.
"""

from __future__ import annotations

import ast
from pathlib import Path

import rnnpb

FOUNDATION = {
    "rnnpb",
    "errors",
    "vectors",
    "_atomic",
    "_fingerprint",
    "_reading",
    "_xla",
    "_interrupt",
}

# part -> the parts it may import (besides itself and the foundation). The model never imports
# the robot, the camera, the screen or the memory store.
ALLOWED: dict[str, set[str]] = {
    "rnnpb": set(),
    "errors": set(),
    "vectors": set(),
    "_atomic": set(),
    "_fingerprint": set(),
    "_reading": set(),
    "_xla": set(),
    "_interrupt": set(),
    "sequences": set(),
    "structure": set(),
    "sources": {"sequences"},
    "robot": set(),
    "bridge": {"robot", "sources"},
    "models": set(),
    "presets": set(),
    "model": {"presets", "sequences", "structure"},
    "memory": {"sequences"},
    "demonstrator": {"robot", "sequences", "sources"},
    "safety": {"demonstrator", "model", "presets", "robot", "sequences"},
    "perception": {"demonstrator", "robot", "sources", "sequences"},
    "mocap": {"demonstrator", "robot", "sources", "sequences"},
    "analysis": {"demonstrator", "robot", "sequences", "structure"},
    "learning_phase": {
        "demonstrator",
        "mocap",
        "perception",
        "robot",
        "safety",
        "sequences",
        "sources",
        "structure",
    },
    "interaction": {
        "learning_phase",
        "bridge",
        "model",
        "presets",
        "memory",
        "safety",
        "perception",
        "demonstrator",
        "robot",
        "sources",
        "sequences",
        "structure",
    },
    "experiments": {
        "learning_phase",
        "analysis",
        "mocap",
        "interaction",
        "model",
        "presets",
        "models",
        "memory",
        "safety",
        "demonstrator",
        "perception",
        "robot",
        "sources",
        "sequences",
    },
    "web": {
        "learning_phase",
        "interaction",
        "models",
        "model",
        "presets",
        "memory",
        "safety",
        "perception",
        "demonstrator",
        "robot",
        "sources",
        "sequences",
        "structure",
        "analysis",
    },
    "sweeps": {
        "learning_phase",
        "experiments",
        "analysis",
        "interaction",
        "model",
        "presets",
        "demonstrator",
        "robot",
        "sources",
        "sequences",
    },
    "commands": {
        "learning_phase",
        "mocap",
        "bridge",
        "models",
        "experiments",
        "sweeps",
        "web",
        "interaction",
        "analysis",
        "model",
        "presets",
        "memory",
        "safety",
        "perception",
        "demonstrator",
        "robot",
        "sources",
        "sequences",
    },
    "cli": set(),
}

ROOT = Path(rnnpb.__file__).parent


def _part(module: str) -> str:
    pieces = module.split(".")
    return "rnnpb" if len(pieces) == 1 else pieces[1]


def _imports() -> dict[str, set[tuple[str, str]]]:
    """part -> {(imported part, file that imports it)}."""
    found: dict[str, set[tuple[str, str]]] = {}
    for path in sorted(ROOT.rglob("*.py")):
        relative = path.relative_to(ROOT.parent).with_suffix("")
        module = ".".join(relative.parts).removesuffix(".__init__")
        part = _part(module)
        edges = found.setdefault(part, set())
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            targets: list[str] = []
            if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                if node.module == "rnnpb":
                    targets = [f"rnnpb.{alias.name}" for alias in node.names]
                elif node.module.startswith("rnnpb."):
                    targets = [node.module]
            elif isinstance(node, ast.Import):
                targets = [a.name for a in node.names if a.name.startswith("rnnpb")]
            for target in targets:
                edges.add((_part(target), str(path.relative_to(ROOT))))
    return found


def test_every_part_has_a_place():
    assert set(_imports()) <= set(ALLOWED), (
        "parts without a place in the layout: "
        f"{sorted(set(_imports()) - set(ALLOWED))} (add them to docs/design.md and ALLOWED)"
    )


def test_imports_point_down():
    wrong = []
    for part, edges in _imports().items():
        allowed = ALLOWED.get(part, set()) | FOUNDATION | {part}
        if part in FOUNDATION - {"rnnpb"}:
            allowed = {part, "errors"}
        if part == "rnnpb":
            allowed = FOUNDATION
        wrong += [
            f"{file} imports rnnpb.{target}"
            for target, file in sorted(edges)
            if target not in allowed and not target.startswith("__")
        ]
    assert not wrong, "imports that run against the layout:\n" + "\n".join(wrong)


def test_the_model_imports_nothing_of_the_world():
    edges = {target for target, _ in _imports()["model"]}
    assert not edges & {"robot", "perception", "web", "memory", "interaction", "demonstrator"}


STUDY_LINES = 400
"""The most lines a study's module may have: it is a runner, a judge and a report over its
scenarios (experiments/scenarios/), which hold the rest."""
FILE_LINES = 800
"""The most lines any module or page script may have."""


def _lines(path: Path) -> int:
    return len(path.read_text(encoding="utf-8").splitlines())


def test_each_study_is_a_short_script():
    long = {
        str(path.relative_to(ROOT)): _lines(path)
        for path in sorted((ROOT / "experiments" / "studies").glob("*.py"))
        if _lines(path) > STUDY_LINES
    }
    assert not long, f"studies over {STUDY_LINES} lines (move a part into scenarios/): {long}"


def test_no_module_is_longer_than_it_can_be_read():
    long = {
        path.relative_to(ROOT).as_posix(): _lines(path)
        for pattern in ("*.py", "*.js")
        for path in sorted(ROOT.rglob(pattern))
        if _lines(path) > FILE_LINES
    }
    assert not long, f"files over {FILE_LINES} lines: {long}"
