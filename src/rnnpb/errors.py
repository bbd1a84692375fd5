"""Errors a user can act on.

Every problem with a user's input (a file, a stream, an option) is raised as a subclass of
:class:`RnnpbError` with a message that names the thing and the problem. The command line prints
that message on one line and exits non-zero; anything else is a bug and keeps its traceback.
"""


class RnnpbError(Exception):
    """Base class of the errors meant for the user, not for a traceback."""


class DataFileError(RnnpbError, ValueError):
    """A data file (sequence CSV, session recording, config) is missing or malformed."""


class ModelFileError(RnnpbError, ValueError):
    """A model file is missing, truncated, foreign, of another format version or mismatched."""


class ConfigError(RnnpbError, ValueError):
    """A configuration value is out of its valid range."""
