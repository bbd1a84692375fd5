"""The dashboard's parts keep to their own: no module reaches into another object's private
members, and no source file of the dashboard (its scripts included) grows past 800 lines."""

from __future__ import annotations

import ast
from pathlib import Path

import rnnpb.web
from rnnpb.web import STATIC_DIR

WEB = Path(rnnpb.web.__file__).parent
MAX_LINES = 800
# A named tuple's own methods start with an underscore and are public.
NAMED_TUPLE = {"_replace", "_asdict", "_fields", "_make"}


def _reaches(tree: ast.AST) -> list[str]:
    """``x._name`` where ``x`` is not the object itself (``self``, ``cls``)."""
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Attribute):
            continue
        name = node.attr
        if not name.startswith("_") or name.startswith("__") or name in NAMED_TUPLE:
            continue
        if isinstance(node.value, ast.Name) and node.value.id in ("self", "cls"):
            continue
        found.append(f"{node.lineno}: {ast.unparse(node)}")
    return found


def test_no_part_of_the_dashboard_reaches_into_another_s_private_members():
    reaches = {
        path.name: _reaches(ast.parse(path.read_text(encoding="utf-8")))
        for path in sorted(WEB.glob("*.py"))
    }
    assert {name: found for name, found in reaches.items() if found} == {}


def test_the_check_sees_a_reach_into_another_object():
    code = "class A:\n    def f(self, other):\n        return self._own, other._theirs\n"
    assert _reaches(ast.parse(code)) == ["3: other._theirs"]


def test_no_source_file_of_the_dashboard_is_over_800_lines():
    files = [*WEB.glob("*.py"), *STATIC_DIR.glob("*.js"), *STATIC_DIR.glob("*.css")]
    files += [*STATIC_DIR.glob("*.html")]
    long = {p.name: n for p in files if (n := len(p.read_text(encoding="utf-8").splitlines()))}
    assert {name: n for name, n in long.items() if n > MAX_LINES} == {}
