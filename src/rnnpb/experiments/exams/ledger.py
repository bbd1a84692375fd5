"""The exam ledger: every exam run, one JSON line each, so that a version is judged once.

``rnnpb study NAME --exam`` writes its run here: a line when it starts (``status``
``"running"``), rewritten when it ends (``"judged"`` with every target's figure and verdict, or
``"failed"`` with the error when it stopped before its verdicts). An entry holds the study, the
exam's version and fingerprint, the code (the checkout's commit and whether its tree had
changes, else the installed package's version), the date, the processor, the exam's draws,
every target's name, measured figure and verdict, and the output directory. Runs made before
the ledger existed are entries too, ``recorded = "notes"``, with the note each comes from and
the figures as it gives them.

Where the ledger lives:

- run from a checkout (the package's own ``ledger.jsonl`` lies in a git work tree that tracks
  it), the checkout's ``src/rnnpb/experiments/exams/ledger.jsonl``, which a commit carries;
- ``--ledger FILE`` (:func:`writable_ledger`) writes to FILE instead; an installed rnnpb (a
  wheel: its package files are not a checkout's) runs no exam without it;
- either way the ledger installed with the package is read too, so that a version judged
  before the package was built stays judged.

A version with a judged run is never run again (:func:`check_may_run`): a changed code is
judged on a new version with fresh draws. A version whose runs all stopped before their
verdicts may run again with ``--rerun-unjudged``, and the new entry names them
(``retry_of``).

Writes are atomic (:func:`rnnpb._atomic.atomic_write`) and, where the system offers ``flock``,
one process at a time.

>>> judged_versions("people")                      # doctest: +SKIP
frozenset({1})

A run reported elsewhere (a note) is added as an entry of its own::

    append(LedgerEntry(
        run="notes-teach-v3-1", study="teach", version=3, fingerprint=exam.fingerprint,
        status="judged", recorded="notes", date="2026-12-08", commit="abc1234", dirty=None,
        rnnpb=None, processor=None, draws=exam_draws(exam),
        targets=(TargetRecord("follow_next_performance", True, 0.95, "19 of 20"),),
        source="notes/2026-12-08-teach.md", note="rnnpb study teach --exam, 180 s"))
"""

from __future__ import annotations

import contextlib
import datetime
import json
import math
import os
import platform
import subprocess
import uuid
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rnnpb._atomic import atomic_write
from rnnpb.errors import ConfigError

if TYPE_CHECKING:
    from rnnpb.experiments.exams import Exam
    from rnnpb.experiments.summary import Target

LEDGER_NAME = "ledger.jsonl"
"""The ledger's file name in this package (and so in a checkout)."""
STATUSES = ("running", "judged", "failed")
"""A run's state: started and not ended (or killed), ended with its verdicts, stopped by an
error before them."""
RECORDED = ("run", "notes")
"""Who wrote an entry: ``rnnpb study --exam`` itself, or the notes of a run made before the
ledger existed."""


@dataclass(frozen=True)
class TargetRecord:
    """One target of a run: its ``name`` (the exam's key), whether it was ``met`` (None: the
    note does not say), the measured ``value`` compared with the limit (None where there is
    none, or the note gives words rather than one number) and ``detail``, the run's own words
    for it — for an entry from the notes, the figure exactly as the note gives it."""

    name: str
    met: bool | None
    value: float | None = None
    detail: str = ""

    def to_json(self) -> dict[str, Any]:
        return {"name": self.name, "met": self.met, "value": self.value, "detail": self.detail}

    @classmethod
    def from_target(cls, name: str, target: Target) -> TargetRecord:
        value = target.value
        if value is not None and not math.isfinite(value):
            value = None
        return cls(name, bool(target.met), None if value is None else float(value), target.detail)


@dataclass(frozen=True)
class LedgerEntry:
    """One exam run (see the module). ``draws`` maps each of the exam's ``[draws]`` keys to
    its list (seeds, or names such as styles); ``out`` is the output directory (absolute) of a
    run, None for one from the notes; ``source`` names the note (and where useful the commit
    that wrote it) an entry from the notes comes from; ``note`` says anything else a reader
    needs (what the figures count, what was not reported)."""

    run: str
    study: str
    version: int
    fingerprint: str
    status: str
    recorded: str
    date: str
    commit: str | None
    dirty: bool | None
    rnnpb: str | None
    processor: str | None
    draws: Mapping[str, Any]
    targets: tuple[TargetRecord, ...] = ()
    out: str | None = None
    source: str = ""
    note: str = ""
    finished: str | None = None
    retry_of: tuple[str, ...] = ()
    error: str = ""

    def __post_init__(self) -> None:
        if self.status not in STATUSES:
            raise ConfigError(f"ledger entry {self.run}: status must be one of {STATUSES}")
        if self.recorded not in RECORDED:
            raise ConfigError(f"ledger entry {self.run}: recorded must be one of {RECORDED}")
        if self.recorded == "notes" and not self.source:
            raise ConfigError(f"ledger entry {self.run}: an entry from the notes names its note")

    @property
    def judged(self) -> bool:
        return self.status == "judged"

    def seeds(self) -> frozenset[int]:
        """Every seed among the entry's draws (the lists of whole numbers)."""
        return frozenset(
            s
            for values in self.draws.values()
            if isinstance(values, list) and all(_whole(v) for v in values)
            for s in values
        )

    def to_json(self) -> dict[str, Any]:
        return {
            "run": self.run,
            "study": self.study,
            "version": self.version,
            "fingerprint": self.fingerprint,
            "status": self.status,
            "recorded": self.recorded,
            "date": self.date,
            "finished": self.finished,
            "commit": self.commit,
            "dirty": self.dirty,
            "rnnpb": self.rnnpb,
            "processor": self.processor,
            "draws": dict(self.draws),
            "targets": [t.to_json() for t in self.targets],
            "out": self.out,
            "source": self.source,
            "note": self.note,
            "retry_of": list(self.retry_of),
            "error": self.error,
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> LedgerEntry:
        """The entry :meth:`to_json` wrote; a missing or mistyped field is a
        :class:`ConfigError` (the caller names the file and line)."""
        try:
            targets = tuple(
                TargetRecord(t["name"], t["met"], t.get("value"), t.get("detail", ""))
                for t in data.get("targets", [])
            )
            entry = cls(
                run=str(data["run"]),
                study=str(data["study"]),
                version=int(data["version"]),
                fingerprint=str(data["fingerprint"]),
                status=str(data["status"]),
                recorded=str(data["recorded"]),
                date=str(data["date"]),
                commit=data.get("commit"),
                dirty=data.get("dirty"),
                rnnpb=data.get("rnnpb"),
                processor=data.get("processor"),
                draws=dict(data.get("draws", {})),
                targets=targets,
                out=data.get("out"),
                source=str(data.get("source", "")),
                note=str(data.get("note", "")),
                finished=data.get("finished"),
                retry_of=tuple(data.get("retry_of", [])),
                error=str(data.get("error", "")),
            )
        except (KeyError, TypeError, ValueError) as error:
            raise ConfigError(f"not a ledger entry ({type(error).__name__}: {error})") from None
        return entry

    def line(self) -> str:
        """The entry as one line of the ledger (no newline)."""
        return json.dumps(self.to_json(), ensure_ascii=False, allow_nan=False)


# --- where the ledger is ------------------------------------------------------------------------


def packaged_ledger() -> Path | None:
    """The ledger installed with the package, as a file path (None if it has none)."""
    file = resources.files(__package__ or "rnnpb.experiments.exams").joinpath(LEDGER_NAME)
    path = Path(str(file))
    return path if path.is_file() else None


def checkout_ledger() -> Path | None:
    """The package's ledger when rnnpb runs from a checkout that tracks it (the file a commit
    carries), else None: an installed package's files are no checkout's, even inside one."""
    path = packaged_ledger()
    if path is None or _checkout() is None:
        return None
    tracked = _git(path.parent, "ls-files", "--error-unmatch", path.name)
    return path if tracked is not None else None


def writable_ledger(requested: str | os.PathLike[str] | None) -> Path:
    """The ledger an exam run writes to: ``requested`` (``--ledger FILE``), else the
    checkout's; an installed rnnpb gives no default, and says so."""
    if requested is not None:
        path = Path(requested)
        if path.is_dir():
            raise ConfigError(f"{path}: is a directory, expected the exam ledger's file")
        return path
    path = checkout_ledger()
    if path is None:
        raise ConfigError(
            "an exam run is written in the exam ledger, and this rnnpb is not run from a "
            "checkout: give --ledger FILE (docs/experiments.md, 'Exams')"
        )
    return path


def ledger_paths(extra: Path | None = None) -> tuple[Path, ...]:
    """The ledgers read to know what was judged: the package's, and ``extra`` if another."""
    paths = [p for p in (packaged_ledger(),) if p is not None]
    if extra is not None and not any(_same_file(extra, p) for p in paths):
        paths.append(extra)
    return tuple(paths)


# --- reading ------------------------------------------------------------------------------------


def read(path: str | os.PathLike[str]) -> list[LedgerEntry]:
    """Every entry of the ledger at ``path`` (none if the file does not exist yet); a
    malformed line is a :class:`ConfigError` naming the file and the line."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        return []
    except (OSError, UnicodeDecodeError) as error:
        raise ConfigError(f"{path}: cannot read the exam ledger ({error})") from None
    entries = []
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip():
            continue
        try:
            entries.append(LedgerEntry.from_json(json.loads(line)))
        except json.JSONDecodeError as error:
            raise ConfigError(f"{path}, line {number}: not JSON ({error.msg})") from None
        except ConfigError as error:
            raise ConfigError(f"{path}, line {number}: {error}") from None
    return entries


def entries(
    study: str | None = None, paths: Sequence[str | os.PathLike[str]] | None = None
) -> list[LedgerEntry]:
    """The entries of ``paths`` (default: the package's ledger), of ``study`` if given, each
    run once (an entry in two files is the same run)."""
    seen: dict[str, LedgerEntry] = {}
    for path in ledger_paths() if paths is None else paths:
        for entry in read(path):
            if study is None or entry.study == study:
                seen[entry.run] = entry
    return list(seen.values())


def judged_versions(
    study: str, paths: Sequence[str | os.PathLike[str]] | None = None
) -> frozenset[int]:
    """The versions of ``study``'s exam with a judged run."""
    return frozenset(e.version for e in entries(study, paths) if e.judged)


def check_may_run(
    exam: Exam, paths: Sequence[str | os.PathLike[str]], rerun_unjudged: bool = False
) -> tuple[str, ...]:
    """Raise :class:`ConfigError` unless ``exam`` may be run: no run of its version was
    judged, and an earlier run that never reached its verdicts is rerun only when asked
    (``rerun_unjudged``). Returns the runs a rerun follows."""
    runs = [e for e in entries(exam.study, paths) if e.version == exam.version]
    judged = [e for e in runs if e.judged]
    if judged:
        first = judged[0]
        raise ConfigError(
            f"the {exam.study} exam's version {exam.version} was judged already (run "
            f"{first.run} of {first.date[:10]}"
            + (f", {len(judged)} judged runs in all" if len(judged) > 1 else "")
            + "): a version is judged once; make a new version with fresh draws "
            "(docs/experiments.md, 'Exams')"
        )
    unjudged = tuple(e.run for e in runs)
    if unjudged and not rerun_unjudged:
        states = ", ".join(f"{e.run} {e.status}" for e in runs)
        raise ConfigError(
            f"the {exam.study} exam's version {exam.version} was started before and never "
            f"judged ({states}): if no such run is still going, --rerun-unjudged runs it again "
            "and the ledger keeps both"
        )
    if rerun_unjudged and not unjudged:
        raise ConfigError(
            f"--rerun-unjudged: the {exam.study} exam's version {exam.version} has no earlier "
            "run to follow"
        )
    return unjudged


# --- writing ------------------------------------------------------------------------------------


def append(entry: LedgerEntry, path: str | os.PathLike[str] | None = None) -> LedgerEntry:
    """Add ``entry`` to the ledger at ``path`` (default: the checkout's); an entry of the
    same run is refused."""
    target = writable_ledger(path)
    with _locked(target):
        lines = _lines(target)
        if any(_run_of(line) == entry.run for line in lines):
            raise ConfigError(f"{target}: holds run {entry.run} already")
        _write(target, [*lines, entry.line()])
    return entry


def replace_entry(entry: LedgerEntry, path: str | os.PathLike[str]) -> LedgerEntry:
    """Rewrite the line of ``entry.run`` in the ledger at ``path`` with ``entry``: a run's
    line changes once, when it ends."""
    target = Path(path)
    with _locked(target):
        lines = _lines(target)
        found = [i for i, line in enumerate(lines) if _run_of(line) == entry.run]
        if len(found) != 1:
            raise ConfigError(f"{target}: holds no single line of run {entry.run}")
        lines[found[0]] = entry.line()
        _write(target, lines)
    return entry


def start(
    exam: Exam,
    out: str | os.PathLike[str],
    path: str | os.PathLike[str],
    retry_of: Iterable[str] = (),
) -> LedgerEntry:
    """Write the start of an exam run (``status`` running) and return its entry."""
    ledger = Path(path)
    commit, dirty, version = code_version(ignore=ledger)
    entry = LedgerEntry(
        run=_now().strftime("%Y%m%dT%H%M%SZ-") + uuid.uuid4().hex[:8],
        study=exam.study,
        version=exam.version,
        fingerprint=exam.fingerprint,
        status="running",
        recorded="run",
        date=_iso(_now()),
        commit=commit,
        dirty=dirty,
        rnnpb=version,
        processor=processor(),
        draws=exam_draws(exam),
        out=str(Path(out).resolve()),
        retry_of=tuple(retry_of),
    )
    return append(entry, ledger)


def finish(
    entry: LedgerEntry,
    path: str | os.PathLike[str],
    targets: Mapping[str, Target] | None = None,
    error: BaseException | None = None,
) -> LedgerEntry:
    """Write the end of ``entry``'s run: judged with ``targets``, or failed with ``error``."""
    done = replace(
        entry,
        status="failed" if targets is None else "judged",
        finished=_iso(_now()),
        targets=tuple(TargetRecord.from_target(k, t) for k, t in (targets or {}).items()),
        error="" if error is None else _error_line(error),
    )
    return replace_entry(done, path)


@contextlib.contextmanager
def exam_run(
    exam: Exam,
    out: str | os.PathLike[str],
    ledger: str | os.PathLike[str] | None = None,
    rerun_unjudged: bool = False,
) -> Iterator[RunRecord]:
    """The ledger around one exam run::

        with exam_run(exam, out, args.ledger) as record:
            outcome = study.run(out, options)
            record.judged(outcome.targets)

    Checks that the version may run (:func:`check_may_run`) against the package's ledger
    and ``ledger`` (default: the checkout's), writes the start, and the end: judged when
    :meth:`RunRecord.judged` was called, else failed with the error that stopped it."""
    from rnnpb.experiments.exams import check_recorded

    check_recorded(exam)
    path = writable_ledger(ledger)
    retry_of = check_may_run(exam, ledger_paths(path), rerun_unjudged)
    record = RunRecord(start(exam, out, path, retry_of), path)
    try:
        yield record
    except BaseException as error:
        record.entry = finish(record.entry, path, error=error)
        raise
    if record.targets is None:
        record.entry = finish(record.entry, path, error=RuntimeError("no verdicts were given"))
    else:
        record.entry = finish(record.entry, path, targets=record.targets)


@dataclass
class RunRecord:
    """An exam run being written (:func:`exam_run`): its entry and ledger, and the verdicts
    once given."""

    entry: LedgerEntry
    path: Path
    targets: Mapping[str, Target] | None = field(default=None)

    def judged(self, targets: Mapping[str, Target]) -> None:
        self.targets = dict(targets)


# --- what the entry records of the run ----------------------------------------------------------


def exam_draws(exam: Exam) -> dict[str, Any]:
    """The exam's draws as its file lists them: seeds, named draws, shapes, learning sets."""
    draws: dict[str, Any] = {k: list(v) for k, v in exam.seeds.items()}
    draws |= {k: list(v) for k, v in exam.names.items()}
    if exam.shapes:
        draws["shapes"] = list(exam.shapes)
    if exam.learning_sets:
        draws["learning_sets"] = list(exam.learning_sets)
    return draws


def code_version(ignore: Path | None = None) -> tuple[str | None, bool | None, str]:
    """The code that runs: the checkout's commit (``git describe --always``, None outside a
    checkout), whether its tree has changes (tracked or untracked, the ledger ``ignore``
    aside; None outside a checkout) and the package's version."""
    from rnnpb import __version__

    here = _checkout()
    described = None if here is None else _git(here, "describe", "--always", "--abbrev=12")
    if here is None or described is None:
        return None, None, __version__
    status = _git(here, "status", "--porcelain")
    top = _git(here, "rev-parse", "--show-toplevel")
    skip = None
    if ignore is not None and top is not None:
        with contextlib.suppress(ValueError):
            skip = Path(ignore).resolve().relative_to(Path(top.strip())).as_posix()
    changed = [line for line in (status or "").splitlines() if line.strip() and line[3:] != skip]
    return described.strip(), bool(changed), __version__


def processor() -> str:
    """The machine's processor, as the system names it, and its cores."""
    name = ""
    with contextlib.suppress(OSError):
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as info:
            for line in info:
                if line.lower().startswith("model name"):
                    name = line.split(":", 1)[1].strip()
                    break
    name = name or platform.processor() or platform.machine() or "unknown"
    return f"{name} ({os.cpu_count() or '?'} cores, {platform.machine()})"


# --- helpers ------------------------------------------------------------------------------------


def _checkout() -> Path | None:
    """This package's folder when a git work tree tracks its code (a checkout, or an
    editable install of one), else None: a wheel installed in a virtual environment that
    lies inside some work tree is not tracked by it."""
    here = Path(__file__).resolve().parent
    tracked = _git(here, "ls-files", "--error-unmatch", "__init__.py")
    return here if tracked is not None else None


def _git(where: Path, *args: str) -> str | None:
    """``git -C where ARGS`` output, None when git or the work tree is not there."""
    try:
        done = subprocess.run(
            ["git", "-C", str(where), *args],
            capture_output=True,
            text=True,
            timeout=30,
            check=False,
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return done.stdout if done.returncode == 0 else None


def _lines(path: Path) -> list[str]:
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        return []
    except (OSError, UnicodeDecodeError) as error:
        raise ConfigError(f"{path}: cannot read the exam ledger ({error})") from None
    return [line for line in text.splitlines() if line.strip()]


def _write(path: Path, lines: list[str]) -> None:
    with atomic_write(path, encoding="utf-8") as handle:
        handle.write("".join(line + "\n" for line in lines))


def _run_of(line: str) -> str | None:
    try:
        return str(json.loads(line).get("run"))
    except (json.JSONDecodeError, AttributeError):
        return None


@contextlib.contextmanager
def _locked(path: Path) -> Iterator[None]:
    """One writer at a time: an exclusive ``flock`` on the ledger's folder (the file itself
    is replaced by every write), where the system has one."""
    try:
        import fcntl
    except ImportError:  # not on this system: writes stay atomic, not exclusive
        yield
        return
    folder = path.parent if str(path.parent) else Path(".")
    folder.mkdir(parents=True, exist_ok=True)
    fd = os.open(folder, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.resolve() == b.resolve()
    except OSError:
        return False


def _whole(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _now() -> datetime.datetime:
    return datetime.datetime.now(datetime.UTC)


def _iso(moment: datetime.datetime) -> str:
    return moment.replace(microsecond=0).isoformat().replace("+00:00", "Z")


def _error_line(error: BaseException) -> str:
    text = str(error).splitlines()[0] if str(error) else ""
    return f"{type(error).__name__}: {text}" if text else type(error).__name__


__all__ = [
    "LEDGER_NAME",
    "RECORDED",
    "STATUSES",
    "LedgerEntry",
    "RunRecord",
    "TargetRecord",
    "append",
    "check_may_run",
    "checkout_ledger",
    "code_version",
    "entries",
    "exam_draws",
    "exam_run",
    "finish",
    "judged_versions",
    "ledger_paths",
    "packaged_ledger",
    "processor",
    "read",
    "replace_entry",
    "start",
    "writable_ledger",
]
