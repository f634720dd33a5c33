"""The fuzz tests' one rule, and the recording behind ``benchmarks/bench_fuzz.py``.

:func:`attempt` runs one call of a public entry point on one generated input
and enforces the contract of the "Reliability" issue: the call either returns
a result (which the caller's ``check`` inspects: finite, well shaped) or
raises one of the project's own exceptions (:class:`CatgraspError`) whose
message is one non-empty line naming the problem. Anything else fails the
test: a numpy/scipy/Drake/open3d/trimesh exception, a ``RuntimeWarning``
(overflow, invalid value: the usual road to NaN output -- turned into an
error here), or a hang (a call running past :data:`HANG_S` seconds is
interrupted by ``SIGALRM``).

Every call is recorded (entry point, input class, outcome, seconds) in
:data:`RECORDS`; ``tests/reliability/conftest.py`` writes them to the file
named by ``CATGRASP_FUZZ_RECORD`` at the end of the session (test-only; the
library knows nothing of it).
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading
import time
import warnings
from dataclasses import dataclass

import numpy as np

from catgrasp_drake.errors import CatgraspError

#: Examples per test in the ci profile (the nightly profile has NIGHTLY_FACTOR times more).
CI_EXAMPLES = 50
NIGHTLY_FACTOR = 10
#: A single call taking longer than this (s) is a hang (interrupted, counted, fails the test).
HANG_S = float(os.environ.get("CATGRASP_FUZZ_HANG_S", "30"))
#: (entry, input class, outcome, seconds, message) of every call; outcome in result/rejected/crash/hang.
RECORDS: list[dict] = []


class Hang(BaseException):
    """Raised by the alarm inside a call that ran past HANG_S (a BaseException: no library
    ``except Exception`` can swallow it)."""


@contextlib.contextmanager
def _time_bound(seconds: float):
    if threading.current_thread() is not threading.main_thread() or not hasattr(signal, "setitimer"):
        yield
        return

    def on_alarm(signum, frame):
        raise Hang()

    old = signal.signal(signal.SIGALRM, on_alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


@dataclass
class Outcome:
    """What one call did: ``value`` (a result) or ``error`` (a project exception)."""

    entry: str
    label: str
    value: object = None
    error: CatgraspError | None = None
    seconds: float = 0.0

    @property
    def rejected(self) -> bool:
        return self.error is not None


def check_message(e: BaseException, *, words: tuple[str, ...] = ()) -> None:
    """A project exception's message: one non-empty line, a sentence (not a bare name), naming
    the problem (contains one of ``words``, case-insensitive, when given)."""
    msg = str(e)
    assert msg.strip(), f"{type(e).__name__} with an empty message"
    assert "\n" not in msg and "\r" not in msg, f"multi-line message: {msg!r}"
    assert len(msg.split()) >= 3, f"message too terse to name the problem: {msg!r}"
    assert len(msg) <= 1000, f"message of {len(msg)} characters: {msg[:200]!r}..."
    if words:
        low = msg.lower()
        assert any(w.lower() in low for w in words), f"message does not name the problem ({words}): {msg!r}"


def attempt(entry: str, label: str, fn, *args, check=None, expect: str | None = None,
            words: tuple[str, ...] = (), **kwargs) -> Outcome:
    """Call ``fn(*args, **kwargs)`` under the contract (module docstring) and record it.

    ``check(value)`` asserts properties of a returned result; ``expect="reject"``
    demands a project exception (input that cannot have a meaningful result),
    ``expect="result"`` demands a result; ``words`` must appear in the message
    of a rejection.
    """
    status, message = "crash", ""
    t0 = time.perf_counter()
    out = Outcome(entry, label)
    try:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error", RuntimeWarning)
                with _time_bound(HANG_S):
                    value = fn(*args, **kwargs)
        except CatgraspError as e:
            out.seconds = time.perf_counter() - t0
            message = str(e)
            check_message(e, words=words)
            assert expect != "result", f"{entry} [{label}]: expected a result, got {type(e).__name__}: {e}"
            out.error = e
            status = "rejected"
            return out
        except Hang:
            status = "hang"
            raise AssertionError(f"{entry} [{label}]: still running after {HANG_S} s (hang)") from None
        out.seconds = time.perf_counter() - t0
        assert expect != "reject", f"{entry} [{label}]: expected a project exception, got a result"
        if check is not None:
            check(value)
        out.value = value
        status = "result"
        return out
    except BaseException as e:
        if status == "crash" and not message:
            message = f"{type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}"
        raise
    finally:
        RECORDS.append({"entry": entry, "label": label, "outcome": status,
                        "seconds": time.perf_counter() - t0, "message": message[:300]})


# ----------------------------------------------------------------------------- result checks
def finite_array(shape=None, *, ndim=None):
    """A check: the value is a finite float ndarray of ``shape`` (None entries match anything)."""

    def check(a):
        assert isinstance(a, np.ndarray), f"expected an ndarray, got {type(a).__name__}"
        assert np.issubdtype(a.dtype, np.number), f"dtype {a.dtype}"
        assert np.all(np.isfinite(a)), "result contains NaN or inf"
        if ndim is not None:
            assert a.ndim == ndim, f"ndim {a.ndim} != {ndim}"
        if shape is not None:
            assert a.ndim == len(shape) and all(s is None or s == t for s, t in zip(shape, a.shape)), \
                f"shape {a.shape} != {shape}"

    return check


def proper_rotations(R, tol: float = 1e-6) -> None:
    """(..., 3, 3) finite, orthonormal, det +1."""
    R = np.asarray(R)
    assert np.all(np.isfinite(R)), "rotation contains NaN or inf"
    RtR = np.swapaxes(R, -1, -2) @ R
    assert np.allclose(RtR, np.eye(3), atol=tol), "rotation is not orthonormal"
    assert np.allclose(np.linalg.det(R), 1.0, atol=tol), "rotation determinant is not +1"


def rigid_poses(X) -> None:
    """(..., 4, 4) finite homogeneous transforms with proper rotations."""
    X = np.asarray(X)
    assert X.shape[-2:] == (4, 4), f"shape {X.shape}"
    assert np.all(np.isfinite(X)), "pose contains NaN or inf"
    proper_rotations(X[..., :3, :3])
    assert np.allclose(X[..., 3, :], [0, 0, 0, 1]), "last row is not [0, 0, 0, 1]"
