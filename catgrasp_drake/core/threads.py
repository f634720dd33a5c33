"""Thread plumbing of the numerical core: worker-thread counts and single-threaded BLAS.

The EM loops (:mod:`catgrasp_drake.core.cpd`, :mod:`catgrasp_drake.core.inference`)
parallelise their E-step with their own threads (:func:`n_threads` of them)
and keep OpenBLAS single-threaded meanwhile (:class:`single_threaded_blas`).
"""

from __future__ import annotations

import ctypes
import functools
import os

#: Environment variable that caps :func:`n_threads` (set to the cores per process in the worker processes
#: of :func:`catgrasp_drake.runner.run_tasks`, whose siblings already share the cores).
THREADS_ENV = "CATGRASP_THREADS"


def n_threads() -> int:
    """Threads of the numerical core's parallel parts (a large E-step's blocks, a shape fit's independent
    starts and hypotheses): the cores, at most 4, at most ``$CATGRASP_THREADS`` when set. Results never
    depend on it (block layouts are fixed by problem size); only time does."""
    n = max(1, min(4, os.cpu_count() or 1))
    cap = os.environ.get(THREADS_ENV, "").strip()
    return min(n, int(cap)) if cap.isdigit() and int(cap) >= 1 else n


#: Run BLAS single-threaded inside the EM loops (see :class:`single_threaded_blas`).
LIMIT_BLAS_THREADS = True


class single_threaded_blas:
    """Context manager: OpenBLAS runs single-threaded inside, restored on exit.

    The EM loops call many small BLAS/LAPACK kernels between numpy ufuncs;
    OpenBLAS's worker threads spin-wait between calls and, when the cores are
    shared (another process running), made CPD 10-20x slower on the 2-core
    test machine (0.3 s -> 6 s for one 500-point drill registration). The
    parallelism that matters (the E-step's exp) is done by the EM code's own
    threads (:func:`n_threads`). Linux + OpenBLAS only (the libraries loaded by numpy and scipy
    are found in /proc/self/maps and driven with ctypes); a no-op elsewhere
    or when :data:`LIMIT_BLAS_THREADS` is False. The setting is process-wide
    while active.
    """

    _libs = None

    @classmethod
    def _find(cls):
        if cls._libs is not None:
            return cls._libs
        libs = []
        try:
            with open("/proc/self/maps") as f:
                paths = sorted({ln.split()[-1] for ln in f if "openblas" in ln.lower() and ".so" in ln})
            for path in paths:
                try:
                    lib = ctypes.CDLL(path)
                except OSError:
                    continue
                for get, set_ in (("scipy_openblas_get_num_threads64_", "scipy_openblas_set_num_threads64_"),
                                  ("scipy_openblas_get_num_threads", "scipy_openblas_set_num_threads"),
                                  ("openblas_get_num_threads64_", "openblas_set_num_threads64_"),
                                  ("openblas_get_num_threads", "openblas_set_num_threads")):
                    if hasattr(lib, get) and hasattr(lib, set_):
                        g, s_ = getattr(lib, get), getattr(lib, set_)
                        g.restype = ctypes.c_int
                        s_.argtypes = [ctypes.c_int]
                        libs.append((g, s_))
                        break
        except OSError:
            libs = []
        cls._libs = libs
        return libs

    def __enter__(self):
        self._saved = []
        if LIMIT_BLAS_THREADS:
            for g, s_ in self._find():
                n = int(g())
                if n > 1:
                    s_(1)
                    self._saved.append((s_, n))
        return self

    def __exit__(self, *exc):
        for s_, n in self._saved:
            s_(n)
        return False


def blas_single_threaded(fn):
    """Decorator: run ``fn`` inside :class:`single_threaded_blas`."""
    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        with single_threaded_blas():
            return fn(*args, **kwargs)

    return wrapper
