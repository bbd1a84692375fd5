"""Count the lines of the model's numerics: every path of the network, the on-line regression
and learning.

The rule: the files of ``src/rnnpb/model`` that compute the network's equations, the on-line
regression or learning in any of their paths — JAX, compiled Python (numba), native code
(LLVM's intermediate language) and the reference — listed in :data:`NUMERICS`; of each, the
lines of code: not blank, not only a comment, not part of a docstring. The settings
(``online_config.py``), the host side of the on-line step (``mirror.py``, ``batched.py``) and
what the numerics serve (recognition, consolidation, routines) are not counted. Also prints
each file's whole length and every file of ``src`` over :data:`LONGEST` lines.

    .venv/bin/python tools/numerics_lines.py [--rev REV]

``--rev`` counts a git revision's files (a file the list names and the revision lacks counts
0) instead of the work tree's.
"""

from __future__ import annotations

import argparse
import ast
import io
import subprocess
import tokenize
from pathlib import Path

NUMERICS = (
    "network.py",
    "parametric_bias.py",
    "meta.py",
    "learning.py",
    "online.py",
    "window.py",
    "reference.py",
    "equations.py",
    "_numba.py",
    "native.py",
    "_ir.py",
    "_learning_ir.py",
    "native_learning.py",
)
"""The files of ``src/rnnpb/model`` counted, past and present."""

LONGEST = 800
ROOT = Path(__file__).resolve().parent.parent


def code_lines(source: str) -> int:
    """The lines of ``source`` that hold code: not blank, not only a comment, not part of a
    docstring (a string alone as a statement)."""
    documentation: set[int] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant):
            if isinstance(node.value.value, str):
                documentation.update(range(node.lineno, (node.end_lineno or node.lineno) + 1))
    code: set[int] = set()
    skipped = {tokenize.COMMENT, tokenize.NL, tokenize.NEWLINE, tokenize.INDENT, tokenize.DEDENT}
    for token in tokenize.generate_tokens(io.StringIO(source).readline):
        if token.type not in skipped and token.type != tokenize.ENDMARKER:
            code.update(range(token.start[0], token.end[0] + 1))
    return len(code - documentation)


def read(path: str, rev: str | None) -> str | None:
    """A file of the work tree, or of revision ``rev``; None where it does not exist."""
    if rev is None:
        file = ROOT / path
        return file.read_text(encoding="utf-8") if file.exists() else None
    shown = subprocess.run(
        ["git", "-C", str(ROOT), "show", f"{rev}:{path}"], capture_output=True, text=True
    )
    return shown.stdout if shown.returncode == 0 else None


def main() -> None:
    parser = argparse.ArgumentParser(description=str(__doc__).splitlines()[0])
    parser.add_argument("--rev", help="a git revision (default: the work tree)")
    args = parser.parse_args()
    total_code = total_lines = 0
    print(f"{'code':>6} {'lines':>6}  file")
    for name in NUMERICS:
        source = read(f"src/rnnpb/model/{name}", args.rev)
        if source is None:
            continue
        code, lines = code_lines(source), len(source.splitlines())
        total_code, total_lines = total_code + code, total_lines + lines
        print(f"{code:6d} {lines:6d}  {name}")
    print(f"{total_code:6d} {total_lines:6d}  the numerics")
    if args.rev is None:
        files = sorted((ROOT / "src").rglob("*.py"))
        texts = {str(f.relative_to(ROOT)): f.read_text(encoding="utf-8") for f in files}
    else:
        listed = subprocess.run(
            ["git", "-C", str(ROOT), "ls-tree", "-r", "--name-only", args.rev, "src"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.split()
        texts = {p: read(p, args.rev) or "" for p in listed if p.endswith(".py")}
    longer = {path: len(text.splitlines()) for path, text in texts.items()}
    longer = {path: n for path, n in longer.items() if n > LONGEST}
    print(
        f"files of src over {LONGEST} lines: "
        + (", ".join(f"{p} ({n})" for p, n in longer.items()) or "none")
    )


if __name__ == "__main__":
    main()
