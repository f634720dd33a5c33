"""The project's own exceptions.

Every error a user can provoke with bad input ends in one of these, with a
one-line message that names the problem and, where possible, what to do.
"""


class CatgraspError(Exception):
    """Base class of all catgrasp_drake errors."""


class InputError(CatgraspError, ValueError):
    """Bad user input: empty/NaN point clouds, wrong units, wrong shapes, unknown names."""


class ModelFileError(CatgraspError, OSError):
    """A model, mesh or data file is missing, unreadable, corrupt or of another format version."""
