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


def one_line(e: BaseException, *, with_type: bool = True, limit: int | None = 160) -> str:
    """The first line of ``e``'s message (at most ``limit`` characters; None: all of it), prefixed by its
    type name.

    For wrapping a third-party exception into one of ours: library messages
    can span many lines (PyYAML, zipfile quoting raw bytes, Drake traces).
    """
    text = str(e).strip()
    first = text.splitlines()[0] if text else ""
    if limit is not None and len(first) > limit:
        first = first[:limit - 3] + "..."
    if not with_type:
        return first or type(e).__name__
    return f"{type(e).__name__}: {first}" if first else type(e).__name__


def run_script(main) -> int:
    """Run a script's ``main()`` the way the ``catgrasp`` command does: a :class:`CatgraspError` (bad input,
    a missing or corrupt file) ends it with one line on stderr and exit status 2, not a traceback."""
    import sys
    from pathlib import Path

    try:
        return int(main() or 0)
    except CatgraspError as e:
        print(f"{Path(sys.argv[0]).name}: error: {one_line(e, with_type=False, limit=None)}", file=sys.stderr)
        return 2
