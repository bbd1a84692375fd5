"""The short-term memory: an embedded SQLite file beside the model holding the episodes the
robot has kept and the rehearsed sequences of each consolidation.

File: ``MODEL.memory.sqlite`` beside ``MODEL.npz`` (:func:`memory_path_for`). SQLite from the
standard library: one file, no server, transactions. Its own files are recognised by
``PRAGMA application_id`` (:data:`APPLICATION_ID`, "RNPB") and their schema by
``PRAGMA user_version`` (:data:`SCHEMA_VERSION`); anything else — another program's database,
a file that is not SQLite, a damaged one, a newer schema — is refused with a
:class:`MemoryFileError` naming the file and the problem, never changed.

Durability: the journal is WAL with ``synchronous=FULL``, and each write is one transaction,
so a process killed at any moment (``kill -9``) loses no committed episode and never leaves the
file inconsistent; an episode is one row holding its whole movement, so there is never half an
episode. Each episode carries a SHA-256 of its arrays, checked when read, so damage that
SQLite's own checks miss is still caught.

Tables (schema 1):

``episodes``
    ``id``, ``created_at`` (Unix seconds), ``source`` (where the movement came from),
    ``model`` (the model that saw it), ``pattern`` (its name once learned, else a proposal),
    ``status`` (``kept``, ``learned``, ``discarded``), ``n_steps``, ``n_cycles``,
    ``sensory`` and ``motor`` (float64 little-endian, (n_steps, 4) and (n_steps, 8)),
    ``digest``, ``note``.
``consolidations``
    ``id``, ``created_at``, ``model_before``, ``model_after``, ``status`` (``done`` or
    ``failed``), ``message``, ``seconds``.
``consolidation_episodes``
    which episodes each consolidation learned.
``rehearsals``
    the sequences each consolidation rehearsed (``pattern``, arrays as above, ``digest``).
"""

from __future__ import annotations

import hashlib
import os
import sqlite3
import time
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rnnpb.errors import DataFileError
from rnnpb.sequences import Sequence, pattern_name_problem
from rnnpb.vectors import MOTOR_SIZE, SENSORY_SIZE

APPLICATION_ID = 0x524E5042  # "RNPB"
SCHEMA_VERSION = 1
STATUSES = ("kept", "learned", "discarded")
CONSOLIDATION_STATUSES = ("done", "failed")
MEMORY_SUFFIX = ".memory.sqlite"
_SQLITE_MAGIC = b"SQLite format 3\x00"
_TEXT_LIMIT = 512

_SCHEMA = f"""
CREATE TABLE episodes (
    id INTEGER PRIMARY KEY,
    created_at REAL NOT NULL,
    source TEXT NOT NULL,
    model TEXT NOT NULL,
    pattern TEXT NOT NULL,
    status TEXT NOT NULL CHECK (status IN {STATUSES!r}),
    n_steps INTEGER NOT NULL CHECK (n_steps >= 2),
    n_cycles INTEGER NOT NULL CHECK (n_cycles >= 0),
    sensory BLOB NOT NULL CHECK (length(sensory) = n_steps * {SENSORY_SIZE * 8}),
    motor BLOB NOT NULL CHECK (length(motor) = n_steps * {MOTOR_SIZE * 8}),
    digest TEXT NOT NULL,
    note TEXT NOT NULL DEFAULT ''
);
CREATE TABLE consolidations (
    id INTEGER PRIMARY KEY,
    created_at REAL NOT NULL,
    model_before TEXT NOT NULL,
    model_after TEXT NOT NULL,
    status TEXT NOT NULL CHECK (status IN {CONSOLIDATION_STATUSES!r}),
    message TEXT NOT NULL DEFAULT '',
    seconds REAL NOT NULL DEFAULT 0
);
CREATE TABLE consolidation_episodes (
    consolidation_id INTEGER NOT NULL REFERENCES consolidations(id) ON DELETE CASCADE,
    episode_id INTEGER NOT NULL REFERENCES episodes(id) ON DELETE CASCADE,
    PRIMARY KEY (consolidation_id, episode_id)
);
CREATE TABLE rehearsals (
    consolidation_id INTEGER NOT NULL REFERENCES consolidations(id) ON DELETE CASCADE,
    position INTEGER NOT NULL,
    pattern TEXT NOT NULL,
    n_steps INTEGER NOT NULL CHECK (n_steps >= 2),
    sensory BLOB NOT NULL CHECK (length(sensory) = n_steps * {SENSORY_SIZE * 8}),
    motor BLOB NOT NULL CHECK (length(motor) = n_steps * {MOTOR_SIZE * 8}),
    digest TEXT NOT NULL,
    PRIMARY KEY (consolidation_id, position)
);
CREATE INDEX episodes_by_status ON episodes (status);
"""


class MemoryFileError(DataFileError):
    """A memory file that is not one, is damaged, or cannot be opened."""


@dataclass(frozen=True)
class EpisodeSummary:
    """What ``rnnpb memory list`` shows of an episode (everything but the arrays)."""

    id: int
    created_at: float
    source: str
    model: str
    pattern: str
    status: str
    n_steps: int
    n_cycles: int
    note: str


@dataclass(frozen=True)
class Episode:
    """A kept movement: whole cycles of what the robot saw and the joint angles for it.

    Attributes
    ----------
    summary : EpisodeSummary
    sensory : array, shape (n_steps, 4)
    motor : array, shape (n_steps, 8)
        Radians.
    """

    summary: EpisodeSummary
    sensory: np.ndarray
    motor: np.ndarray

    @property
    def id(self) -> int:
        return self.summary.id

    def sequence(self, pattern: str | None = None) -> Sequence:
        """The episode as a training :class:`Sequence` (of its pattern unless one is given)."""
        return Sequence(
            self.sensory,
            self.motor,
            pattern or self.summary.pattern,
            f"memory episode {self.summary.id}",
        )


@dataclass(frozen=True)
class ConsolidationSummary:
    """One consolidation the memory took part in."""

    id: int
    created_at: float
    model_before: str
    model_after: str
    status: str
    message: str
    seconds: float
    episode_ids: tuple[int, ...]
    n_rehearsed: int


def memory_path_for(model_path: str | os.PathLike[str]) -> Path:
    """``model.npz`` → ``model.memory.sqlite`` (beside it)."""
    path = Path(model_path)
    if path.name.endswith(MEMORY_SUFFIX):
        return path
    return path.with_name(path.name.removesuffix(".npz") + MEMORY_SUFFIX)


def _digest(sensory: bytes, motor: bytes) -> str:
    return hashlib.sha256(sensory + b"|" + motor).hexdigest()


def _arrays(sensory: np.ndarray, motor: np.ndarray, where: str) -> tuple[bytes, bytes, int]:
    sensory = np.asarray(sensory, dtype="<f8")
    motor = np.asarray(motor, dtype="<f8")
    # the Sequence checks shapes, lengths and finiteness with the messages every file gets
    Sequence(sensory, motor, "episode", where)
    return sensory.tobytes(), motor.tobytes(), int(len(sensory))


def _text(value: object, name: str) -> str:
    text = str(value)
    if len(text) > _TEXT_LIMIT or any(ord(c) < 32 and c not in "\t" for c in text):
        raise DataFileError(f"memory: {name} must be at most {_TEXT_LIMIT} printable characters")
    return text


def _joined(note: str, part: str) -> str:
    """``note`` with ``part`` added (parts are separated by "; "), the oldest parts dropped
    past the length a note may have."""
    parts = [p for p in note.split("; ") if p] + [part]
    while len(parts) > 1 and len("; ".join(parts)) > _TEXT_LIMIT:
        del parts[1]  # the first part says which steps the episode was cut from
    return "; ".join(parts)[:_TEXT_LIMIT]


def _pattern(name: str) -> str:
    problem = pattern_name_problem(name)
    if problem:
        raise DataFileError(f"memory: pattern name {name!r} {problem}")
    return name


class MemoryStore:
    """The short-term memory file (a context manager).

    Parameters
    ----------
    path : path
        The ``.memory.sqlite`` file (or a model path: the file beside it).
    create : bool
        Create the file when it does not exist (otherwise a missing file is an error).

    Examples
    --------
    >>> with MemoryStore("model.npz") as memory:                   # doctest: +SKIP
    ...     episode_id = memory.add_episode(sensory, motor, source="webcam:0",
    ...                                     model="model.npz", pattern="new-1", n_cycles=4)
    """

    def __init__(self, path: str | os.PathLike[str], create: bool = True) -> None:
        self.path = memory_path_for(path)
        self._connection: sqlite3.Connection | None = None
        self._create = create

    # --- opening ------------------------------------------------------------------------
    def open(self) -> MemoryStore:
        if self._connection is not None:
            return self
        path = self.path
        exists = path.exists()
        if exists:
            self._check_file(path)
        elif not self._create:
            raise MemoryFileError(f"{path}: no such memory file")
        try:
            connection = sqlite3.connect(
                path, timeout=10.0, isolation_level=None, check_same_thread=False
            )
        except sqlite3.Error as error:
            raise MemoryFileError(f"{path}: cannot open the memory file: {error}") from None
        try:
            self._prepare(connection, path)
        except BaseException:
            connection.close()
            raise
        self._connection = connection
        return self

    @staticmethod
    def _check_file(path: Path) -> None:
        if not path.is_file():
            raise MemoryFileError(f"{path}: is not a regular file")
        with open(path, "rb") as handle:
            head = handle.read(len(_SQLITE_MAGIC))
        if head and head != _SQLITE_MAGIC:
            raise MemoryFileError(f"{path}: is not a memory file (not an SQLite database)")

    def _prepare(self, connection: sqlite3.Connection, path: Path) -> None:
        try:
            connection.execute("PRAGMA busy_timeout = 10000")
            application_id = connection.execute("PRAGMA application_id").fetchone()[0]
            version = connection.execute("PRAGMA user_version").fetchone()[0]
            tables = connection.execute(
                "SELECT count(*) FROM sqlite_schema WHERE type = 'table'"
            ).fetchone()[0]
        except sqlite3.DatabaseError as error:
            raise MemoryFileError(f"{path}: is damaged or not a memory file: {error}") from None
        if application_id == 0 and version == 0 and tables == 0:
            self._initialise(connection, path)
            return
        if application_id != APPLICATION_ID:
            raise MemoryFileError(
                f"{path}: is another program's SQLite database, not an rnnpb "
                f"memory file (application_id {application_id:#x})"
            )
        if version > SCHEMA_VERSION:
            raise MemoryFileError(
                f"{path}: memory schema {version} is newer than this rnnpb "
                f"reads ({SCHEMA_VERSION}); upgrade rnnpb"
            )
        if version < 1:
            raise MemoryFileError(f"{path}: memory schema {version} is unknown")
        try:
            problems = [row[0] for row in connection.execute("PRAGMA quick_check")]
            connection.execute("PRAGMA journal_mode = WAL")
            connection.execute("PRAGMA synchronous = FULL")
            connection.execute("PRAGMA foreign_keys = ON")
        except sqlite3.DatabaseError as error:
            raise MemoryFileError(f"{path}: is damaged: {error}") from None
        if problems != ["ok"]:
            raise MemoryFileError(f"{path}: is damaged: {problems[0]}")

    @staticmethod
    def _initialise(connection: sqlite3.Connection, path: Path) -> None:
        try:
            connection.execute("PRAGMA journal_mode = WAL")
            connection.execute("PRAGMA synchronous = FULL")
            connection.execute("PRAGMA foreign_keys = ON")
            connection.execute("BEGIN IMMEDIATE")
            # PRAGMAs inside the transaction: a new file is either whole or still empty
            connection.execute(f"PRAGMA application_id = {APPLICATION_ID}")
            connection.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
            for statement in _SCHEMA.split(";"):
                if statement.strip():
                    connection.execute(statement)
            connection.execute("COMMIT")
        except sqlite3.Error as error:
            if connection.in_transaction:
                connection.execute("ROLLBACK")
            raise MemoryFileError(f"{path}: cannot create the memory file: {error}") from None

    def close(self) -> None:
        if self._connection is not None:
            self._connection.close()
            self._connection = None

    def __enter__(self) -> MemoryStore:
        return self.open()

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    @property
    def _db(self) -> sqlite3.Connection:
        if self._connection is None:
            self.open()
        assert self._connection is not None
        return self._connection

    def _write(self, statements):
        """Run ``statements(connection)`` as one transaction (all or nothing)."""
        db = self._db
        try:
            db.execute("BEGIN IMMEDIATE")
            try:
                result = statements(db)
            except BaseException:
                db.execute("ROLLBACK")
                raise
            db.execute("COMMIT")
        except sqlite3.Error as error:
            raise MemoryFileError(f"{self.path}: write failed: {error}") from None
        return result

    # --- episodes ----------------------------------------------------------------------
    def add_episode(
        self,
        sensory: np.ndarray,
        motor: np.ndarray,
        *,
        source: str,
        model: str,
        pattern: str,
        n_cycles: int,
        status: str = "kept",
        note: str = "",
        created_at: float | None = None,
    ) -> int:
        """Store one episode (one transaction); returns its id.

        ``sensory`` (n_steps, 4) and ``motor`` (n_steps, 8, radians) are whole cycles of the
        movement, all finite.
        """
        if status not in STATUSES:
            raise DataFileError(
                f"memory: status must be one of {', '.join(STATUSES)}, got {status!r}"
            )
        if n_cycles < 0:
            raise DataFileError(f"memory: n_cycles must be >= 0, got {n_cycles}")
        s, m, n = _arrays(sensory, motor, f"memory episode from {source}")
        row = (
            time.time() if created_at is None else float(created_at),
            _text(source, "source"),
            _text(model, "model"),
            _pattern(pattern),
            status,
            n,
            int(n_cycles),
            s,
            m,
            _digest(s, m),
            _text(note, "note"),
        )
        return self._write(
            lambda db: (
                db.execute(
                    "INSERT INTO episodes (created_at, source, model, pattern, status, n_steps, "
                    "n_cycles, sensory, motor, digest, note) VALUES (?,?,?,?,?,?,?,?,?,?,?)",
                    row,
                ).lastrowid
            )
        )

    def regrow(
        self, episode_id: int, sensory: np.ndarray, motor: np.ndarray, n_cycles: int, note: str
    ) -> bool:
        """Put a longer stretch of the same performance in a ``kept`` episode's place (one
        transaction); False, and nothing changed, when the episode is no longer ``kept``
        (learned, discarded or forgotten): what was learned stays what it was. The caller
        keeps an episode a running consolidation reads from growing."""
        if n_cycles < 0:
            raise DataFileError(f"memory: n_cycles must be >= 0, got {n_cycles}")
        s, m, n = _arrays(sensory, motor, f"memory episode {episode_id}")
        row = (n, int(n_cycles), s, m, _digest(s, m), _text(note, "note"), int(episode_id))
        return bool(
            self._write(
                lambda db: (
                    db.execute(
                        "UPDATE episodes SET n_steps = ?, n_cycles = ?, sensory = ?, motor = ?, "
                        "digest = ?, note = ? WHERE id = ? AND status = 'kept'",
                        row,
                    ).rowcount
                )
            )
        )

    def episodes(self, status: str | None = None) -> list[EpisodeSummary]:
        """Every episode (of one status), oldest first, without the arrays."""
        query = (
            "SELECT id, created_at, source, model, pattern, status, n_steps, n_cycles, "
            "note FROM episodes"
        )
        arguments: tuple = ()
        if status is not None:
            query += " WHERE status = ?"
            arguments = (status,)
        rows = self._read(query + " ORDER BY id", arguments)
        return [EpisodeSummary(*row) for row in rows]

    def episode(self, episode_id: int) -> Episode:
        """One episode with its arrays; raises :class:`MemoryFileError` when absent or damaged."""
        rows = self._read(
            "SELECT id, created_at, source, model, pattern, status, n_steps, "
            "n_cycles, note, sensory, motor, digest FROM episodes WHERE id = ?",
            (int(episode_id),),
        )
        if not rows:
            raise MemoryFileError(f"{self.path}: no episode {episode_id}")
        *fields, sensory, motor, digest = rows[0]
        summary = EpisodeSummary(*fields)
        return Episode(
            summary, *self._decode(sensory, motor, digest, summary.n_steps, f"episode {episode_id}")
        )

    def _decode(
        self, sensory: bytes, motor: bytes, digest: str, n_steps: int, what: str
    ) -> tuple[np.ndarray, np.ndarray]:
        if _digest(sensory, motor) != digest:
            raise MemoryFileError(f"{self.path}: {what} is damaged (its checksum does not match)")
        return (
            np.frombuffer(sensory, "<f8").reshape(n_steps, SENSORY_SIZE).copy(),
            np.frombuffer(motor, "<f8").reshape(n_steps, MOTOR_SIZE).copy(),
        )

    def set_status(self, episode_id: int, status: str) -> None:
        if status not in STATUSES:
            raise DataFileError(f"memory: status must be one of {', '.join(STATUSES)}")
        self._change(
            "UPDATE episodes SET status = ? WHERE id = ?", (status, int(episode_id)), episode_id
        )

    def unlearn(self, model_after: str | os.PathLike[str]) -> list[int]:
        """The episodes a consolidation into ``model_after`` learned are ``kept`` again (that
        version was undone): one transaction; returns their ids. Episodes since forgotten or
        discarded are left as they are."""
        target = Path(model_after).resolve()
        ids = sorted(
            {
                episode_id
                for c in self.consolidations()
                if c.status == "done" and c.model_after and Path(c.model_after).resolve() == target
                for episode_id in c.episode_ids
            }
        )

        def statements(db: sqlite3.Connection) -> list[int]:
            back = []
            for episode_id in ids:
                changed = db.execute(
                    "UPDATE episodes SET status = 'kept' WHERE id = ? AND status = 'learned'",
                    (episode_id,),
                ).rowcount
                if changed:
                    back.append(episode_id)
            return back

        return self._write(statements)

    def rename(self, episode_id: int, pattern: str) -> None:
        self._change(
            "UPDATE episodes SET pattern = ? WHERE id = ?",
            (_pattern(pattern), int(episode_id)),
            episode_id,
        )

    def group(self, pattern: str, statuses: Iterable[str] = ("kept", "learned")) -> list[int]:
        """The ids of the episodes of one movement (the episodes named ``pattern``), of these
        statuses, oldest first."""
        wanted = tuple(statuses)
        return [e.id for e in self.episodes() if e.pattern == pattern and e.status in wanted]

    def merge(self, episode_id: int, into: int, why: str = "") -> str:
        """Episode ``episode_id`` is another performance of episode ``into``'s movement: it
        takes that episode's pattern name, and its note says so (``why``: how alike they
        are). One transaction; returns the pattern. A learned episode is not moved (it is
        part of a model version already: forget or undo that version first)."""
        target = self.episode_summary(into)
        moved = self.episode_summary(episode_id)
        if moved.status == "learned":
            raise DataFileError(
                f"memory: episode {episode_id} is learned as {moved.pattern!r}; it cannot join "
                "another movement"
            )
        if episode_id == into or moved.pattern == target.pattern:
            return target.pattern
        note = _joined(moved.note, f"merged with episode {into}" + (f" ({why})" if why else ""))
        self._change(
            "UPDATE episodes SET pattern = ?, note = ? WHERE id = ?",
            (target.pattern, _text(note, "note"), int(episode_id)),
            episode_id,
        )
        return target.pattern

    def split(self, episode_id: int, pattern: str) -> None:
        """Episode ``episode_id`` is a movement of its own after all (a merge undone): it is
        named ``pattern``, which no other episode may carry. A learned episode is not moved."""
        moved = self.episode_summary(episode_id)
        if moved.status == "learned":
            raise DataFileError(
                f"memory: episode {episode_id} is learned as {moved.pattern!r}; it cannot be "
                "split from it"
            )
        if any(e.pattern == pattern for e in self.episodes() if e.id != episode_id):
            raise DataFileError(f"memory: the name {pattern!r} is taken by another episode")
        note = _joined(moved.note, f"split from {moved.pattern}")
        self._change(
            "UPDATE episodes SET pattern = ?, note = ? WHERE id = ?",
            (_pattern(pattern), _text(note, "note"), int(episode_id)),
            episode_id,
        )

    def episode_summary(self, episode_id: int) -> EpisodeSummary:
        """One episode without its arrays; raises :class:`MemoryFileError` when absent."""
        rows = self._read(
            "SELECT id, created_at, source, model, pattern, status, n_steps, n_cycles, "
            "note FROM episodes WHERE id = ?",
            (int(episode_id),),
        )
        if not rows:
            raise MemoryFileError(f"{self.path}: no episode {episode_id}")
        return EpisodeSummary(*rows[0])

    def forget(self, episode_id: int) -> None:
        """Delete an episode and its movement (the consolidations keep their rehearsals)."""
        self._change("DELETE FROM episodes WHERE id = ?", (int(episode_id),), episode_id)

    def _change(self, statement: str, arguments: tuple, episode_id: int) -> None:
        changed = self._write(lambda db: db.execute(statement, arguments).rowcount)
        if not changed:
            raise MemoryFileError(f"{self.path}: no episode {episode_id}")

    # --- consolidations ------------------------------------------------------------------
    def add_consolidation(
        self,
        *,
        model_before: str,
        model_after: str,
        episode_ids: Iterable[int],
        rehearsed: Iterable[Sequence],
        status: str = "done",
        message: str = "",
        seconds: float = 0.0,
    ) -> int:
        """Record one consolidation and the sequences it rehearsed (one transaction).

        When ``status`` is ``done`` its episodes become ``learned``.
        """
        if status not in CONSOLIDATION_STATUSES:
            raise DataFileError(
                f"memory: consolidation status must be one of {', '.join(CONSOLIDATION_STATUSES)}"
            )
        ids = [int(i) for i in episode_ids]
        rows = []
        for position, sequence in enumerate(rehearsed):
            s, m, n = _arrays(sequence.sensory, sequence.motor, "memory rehearsal")
            rows.append((position, _pattern(sequence.pattern), n, s, m, _digest(s, m)))

        def statements(db: sqlite3.Connection) -> int:
            consolidation = db.execute(
                "INSERT INTO consolidations (created_at, model_before, model_after, status, "
                "message, seconds) VALUES (?,?,?,?,?,?)",
                (
                    time.time(),
                    _text(model_before, "model"),
                    _text(model_after, "model"),
                    status,
                    _text(message, "message"),
                    float(seconds),
                ),
            ).lastrowid
            for episode_id in ids:
                if (
                    db.execute("SELECT 1 FROM episodes WHERE id = ?", (episode_id,)).fetchone()
                    is None
                ):
                    raise MemoryFileError(f"{self.path}: no episode {episode_id}")
                db.execute(
                    "INSERT INTO consolidation_episodes VALUES (?, ?)", (consolidation, episode_id)
                )
                if status == "done":
                    db.execute("UPDATE episodes SET status = 'learned' WHERE id = ?", (episode_id,))
            db.executemany(
                "INSERT INTO rehearsals VALUES (?,?,?,?,?,?,?)",
                [(consolidation, *row) for row in rows],
            )
            return consolidation

        return self._write(statements)

    def consolidations(self) -> list[ConsolidationSummary]:
        rows = self._read(
            "SELECT id, created_at, model_before, model_after, status, message, "
            "seconds FROM consolidations ORDER BY id"
        )
        out = []
        for row in rows:
            episodes = tuple(
                r[0]
                for r in self._read(
                    "SELECT episode_id FROM consolidation_episodes WHERE consolidation_id = ? "
                    "ORDER BY episode_id",
                    (row[0],),
                )
            )
            count = self._read(
                "SELECT count(*) FROM rehearsals WHERE consolidation_id = ?", (row[0],)
            )[0][0]
            out.append(ConsolidationSummary(*row, episode_ids=episodes, n_rehearsed=count))
        return out

    def rehearsed(self, consolidation_id: int) -> list[Sequence]:
        """The sequences a consolidation rehearsed, in order."""
        rows = self._read(
            "SELECT position, pattern, n_steps, sensory, motor, digest FROM "
            "rehearsals WHERE consolidation_id = ? ORDER BY position",
            (int(consolidation_id),),
        )
        out = []
        for position, pattern, n, sensory, motor, digest in rows:
            s, m = self._decode(
                sensory,
                motor,
                digest,
                n,
                f"rehearsal {position} of consolidation {consolidation_id}",
            )
            out.append(
                Sequence(s, m, pattern, f"consolidation {consolidation_id} rehearsal {position}")
            )
        return out

    def integrity(self) -> str:
        """SQLite's ``PRAGMA integrity_check``: ``"ok"`` or the first problem."""
        return str(self._read("PRAGMA integrity_check")[0][0])

    def _read(self, query: str, arguments: tuple = ()) -> list[tuple]:
        try:
            return self._db.execute(query, arguments).fetchall()
        except sqlite3.DatabaseError as error:
            raise MemoryFileError(f"{self.path}: is damaged: {error}") from None
