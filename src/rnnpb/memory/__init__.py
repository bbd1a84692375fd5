"""The short-term memory: the episodes the robot has kept and the rehearsals of each
consolidation, in one SQLite file beside the model (docs/teaching.md).

The memory knows no network: it imports only the foundation and :mod:`rnnpb.sequences`.
"""

from rnnpb.memory._store import (
    APPLICATION_ID,
    CONSOLIDATION_STATUSES,
    MEMORY_SUFFIX,
    SCHEMA_VERSION,
    STATUSES,
    ConsolidationSummary,
    Episode,
    EpisodeSummary,
    MemoryFileError,
    MemoryStore,
    memory_path_for,
)

__all__ = [
    "APPLICATION_ID",
    "CONSOLIDATION_STATUSES",
    "MEMORY_SUFFIX",
    "SCHEMA_VERSION",
    "STATUSES",
    "ConsolidationSummary",
    "Episode",
    "EpisodeSummary",
    "MemoryFileError",
    "MemoryStore",
    "memory_path_for",
]
