"""Run many independent tasks (grasp trials) in parallel with an on-disk cache.

Training and evaluation are made of independent trials. This module runs a
pure task function over JSON-able task specs in worker processes and stores
every finished result as its own small JSON file, written atomically, named by
the hash of (task spec, code fingerprint). Hence:

* re-running never recomputes what is already known (same spec, same code);
* a run killed at any moment (even ``kill -9``) resumes without losing or
  double-counting a finished task: a result file either exists whole or not;
* a task that raises (including the ``SystemExit`` that pydrake raises for a
  failed ``DRAKE_DEMAND`` inside Drake) becomes a result
  ``{"status": "error", "error": ...}`` rather than a dead run; a worker
  process that dies outright (segfault, OOM kill) does not take the run with
  it: the tasks it may have been running are re-run one at a time in a fresh
  worker, and the one that kills its worker again becomes an error result
  (not cached, so a later run tries it again).

Every cache file carries a format name, a format version and a sha256 of its
content; an unreadable, truncated, edited or foreign file is recomputed (and
atomically overwritten), never trusted.

The task function must be a module-level callable (importable by workers)
taking the spec dict and returning a JSON-able dict.
"""

from __future__ import annotations

import hashlib
import json
import os
import signal
import sys
import traceback
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from multiprocessing import get_context
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping, Sequence

from catgrasp_drake.core.fileio import atomic_write_text
from catgrasp_drake.errors import InputError, one_line


def canonical_json(obj: Any) -> str:
    """Deterministic JSON text (sorted keys, no spaces) used for hashing."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), allow_nan=False)


def code_fingerprint(paths: Sequence[str | os.PathLike]) -> str:
    """sha256 of the CONTENTS of the given files and directories (recursively): a cache's "code version".

    Change any file that can change a trial's outcome and the cached results are
    no longer reused. Each file contributes the sha256 of its bytes; a data file
    (anything but ``.py``) also contributes its path relative to the listed path
    it was found under (a data set's own names matter: ``drill_00.obj`` is
    drill_00's mesh), a Python module does not (its name matters only to what
    imports it, and that is hashed too). The contributions are sorted, so the
    fingerprint depends neither on where the repository lives, nor on the order
    of ``paths``, nor on which module a function lives in: moving code between
    files without editing it keeps the caches. Files listed twice count once;
    ``__pycache__`` and ``.pyc`` are skipped.
    """
    entries = {}
    for root in paths:
        root = Path(root)
        files = sorted(p for p in root.rglob("*") if p.is_file()) if root.is_dir() else [root]
        for p in files:
            if p.suffix == ".pyc" or "__pycache__" in p.parts:
                continue
            name = "" if p.suffix == ".py" else (p.relative_to(root).as_posix() if root.is_dir() else p.name)
            digest = hashlib.sha256(p.read_bytes()).hexdigest()
            entries[p.resolve()] = hashlib.sha256(f"{name}\0{digest}".encode()).hexdigest()
    h = hashlib.sha256()
    for entry in sorted(entries.values()):
        h.update(entry.encode())
    return h.hexdigest()[:16]


def task_key(spec: Mapping[str, Any], code_version: str) -> str:
    """The cache key of ``spec`` under ``code_version``. Fields whose name begins with ``_`` are not part of it:
    where an input lives (e.g. ``_model``, a model file's path) when its content is in the spec under another
    field (``model_sha256``), so the same model at another path reuses its trials."""
    keyed = {k: v for k, v in spec.items() if not k.startswith("_")}
    return hashlib.sha256((code_version + canonical_json(keyed)).encode()).hexdigest()[:24]


@dataclass(frozen=True)
class TaskOutcome:
    """One task's spec and result; ``cached`` tells whether it came from disk."""

    key: str
    spec: dict
    result: dict
    cached: bool


def _run_one(fn: Callable[[dict], dict], spec: dict) -> dict:
    try:
        result = fn(spec)
        if not isinstance(result, dict):
            raise TypeError(f"task function returned {type(result).__name__}, expected dict")
        result.setdefault("status", "ok")
        json.dumps(result)  # must be storable: a result that is not JSON-able is an error, not a dead run
        return result
    # a failed trial is an outcome, not a dead run. SystemExit too: pydrake turns a failed
    # DRAKE_DEMAND/DRAKE_THROW (e.g. a mesh face with an out-of-range vertex) into SystemExit.
    except (Exception, SystemExit) as e:
        return {
            "status": "error",
            "error": one_line(e, limit=500),
            "traceback": traceback.format_exc(limit=5)[-2000:],
        }


#: A worker process is replaced by a fresh one after this many tasks. Drake 1.51's Python-defined LeafSystems
#: are never freed once added to a DiagramBuilder, even one with no ports or callbacks (the builder and the
#: system name each other, and the builder's C++ side holds the system where the collector cannot see it;
#: RobotLocomotion/drake #22515, #24162; the canary ``tests/runner/test_runner.py`` says when a Drake release
#: fixes it): every grasp trial leaves its diagrams alive, ~45 MB, and a 648-trial benchmark grew two
#: workers to 11 GB each and stalled a 23 GB machine (session 34). Replaced every 20 tasks, a worker stays under
#: ~1.3 GB; a respawn costs ~2 s per 20 trials of 2-8 s each (imports and the model 0.7-0.9 s, the first
#: trial's warm-up ~1 s). (Python >= 3.11; on 3.10 the workers live for the whole run.)
WORKER_TASKS = 20

#: Format of the cache files (``TaskCache``).
CACHE_FORMAT = "catgrasp.task_result"
CACHE_FORMAT_VERSION = 1


def _record_checksum(record: Mapping[str, Any]) -> str:
    body = {k: record.get(k) for k in ("key", "code_version", "spec", "result")}
    return hashlib.sha256(json.dumps(body, sort_keys=True, separators=(",", ":")).encode()).hexdigest()


class TaskCache:
    """A directory of ``<key>.json`` result files."""

    def __init__(self, directory: str | os.PathLike, code_version: str):
        self.directory = Path(directory)
        self.code_version = code_version
        self.directory.mkdir(parents=True, exist_ok=True)

    def path(self, key: str) -> Path:
        return self.directory / f"{key}.json"

    def get(self, key: str) -> dict | None:
        """The cached result of ``key``, or None when absent, of another code version, or not a whole,
        valid cache file (unreadable, truncated, edited: it is then recomputed and overwritten)."""
        p = self.path(key)
        try:
            record = json.loads(p.read_text(encoding="utf-8"))
        except FileNotFoundError:
            return None
        except (OSError, ValueError):  # unreadable, not UTF-8, not JSON: recompute
            return None
        if not isinstance(record, dict) or record.get("key") != key:
            return None
        if record.get("code_version") != self.code_version or not isinstance(record.get("result"), dict):
            return None
        if "format" in record or "sha256" in record:  # files without them predate the checksum: trusted as before
            if (record.get("format") != CACHE_FORMAT or record.get("format_version") != CACHE_FORMAT_VERSION
                    or record.get("sha256") != _record_checksum(record)):
                return None
        return record["result"]

    def put(self, key: str, spec: dict, result: dict) -> None:
        record = {"format": CACHE_FORMAT, "format_version": CACHE_FORMAT_VERSION, "key": key,
                  "code_version": self.code_version, "spec": spec, "result": result}
        record["sha256"] = _record_checksum(record)
        atomic_write_text(self.path(key), json.dumps(record, sort_keys=True, indent=1) + "\n")


def run_tasks(
    fn: Callable[[dict], dict],
    specs: Iterable[Mapping[str, Any]],
    *,
    cache_dir: str | os.PathLike | None,
    code_version: str,
    workers: int | None = None,
    progress: Callable[[TaskOutcome, int, int], None] | None = None,
    ray_address: str | None = None,
) -> list[TaskOutcome]:
    """Run ``fn`` on every spec (cached ones are read back), returning outcomes in spec order.

    ``workers``: number of processes (default: all cores; 0 or 1 runs in this
    process). ``progress(outcome, done, total)`` is called after each task.
    ``ray_address``: run the tasks on a Ray cluster instead (``"auto"``: the
    running cluster, ``"local"``: start one on this machine, else the head's
    address; needs the optional extra ``.[cluster]``): the same task function
    on the same specs, results cached the same way, so a run may switch
    between local workers and Ray and resume either way.
    Specs must be JSON-able dicts; duplicates are run once.
    """
    specs = [dict(s) for s in specs]
    for s in specs:
        try:
            canonical_json(s)
        except (TypeError, ValueError) as e:
            raise InputError(f"task spec is not JSON-able ({e}): {s!r:.200}") from None
    keys = [task_key(s, code_version) for s in specs]
    spec_of = dict(zip(keys, specs))
    cache = TaskCache(cache_dir, code_version) if cache_dir is not None else None
    results: dict[str, tuple[dict, bool]] = {}
    todo: dict[str, dict] = {}
    for k, s in zip(keys, specs):
        if k in results or k in todo:
            continue
        cached = cache.get(k) if cache else None
        if cached is not None:
            results[k] = (cached, True)
        else:
            todo[k] = s
    total = len(set(keys))
    done = 0

    def finish(k: str, result: dict, cached: bool) -> None:
        nonlocal done
        if cache and not cached and not result.get("worker_died"):  # a dead worker may be transient: retry later
            cache.put(k, todo[k], result)
        results[k] = (result, cached)
        done += 1
        if progress is not None:
            progress(TaskOutcome(k, spec_of[k], result, cached), done, total)

    for k in list(results):
        done += 1
        if progress is not None:
            progress(TaskOutcome(k, spec_of[k], results[k][0], True), done, total)

    n_workers = (os.cpu_count() or 1) if workers is None else int(workers)
    if ray_address is not None and todo:
        _run_on_ray(fn, todo, finish, ray_address, n_workers)
    elif n_workers <= 1 or len(todo) <= 1:
        for k, s in todo.items():
            finish(k, _run_one(fn, s), False)
    else:
        _run_in_processes(fn, todo, finish, n_workers)
    return [TaskOutcome(k, spec_of[k], *results[k]) for k in keys]


def _dead_worker_result(exitcode: int | None) -> dict:
    if exitcode is not None and exitcode < 0:
        try:
            how = f"was killed by {signal.Signals(-exitcode).name}"
        except ValueError:
            how = f"was killed by signal {-exitcode}"
    else:
        how = f"ended with exit code {exitcode}" if exitcode is not None else "died"
    return {"status": "error", "error": f"WorkerDied: the worker process running this task {how}",
            "worker_died": True}


def _share_cores(threads: int) -> None:
    """Worker-process initializer: cap the numerical core's threads (``core.threads.THREADS_ENV``)."""
    from catgrasp_drake.core.threads import THREADS_ENV

    os.environ[THREADS_ENV] = str(threads)


def _pool_round(fn, todo: dict, finish, n_workers: int) -> tuple[list[str], int | None]:
    """Run ``todo`` in one pool of spawned workers, at most ``n_workers`` tasks submitted at a time (so a
    submitted task is a running one); finished tasks are reported through ``finish``. Returns
    ``([], None)`` when all finished, else, when a worker died, the keys that were in flight and a dead
    worker's exit code (the tasks never started are simply not reported)."""
    queue = list(todo)
    n_procs = min(n_workers, len(queue))
    # the processes share the cores: each one's numerical core gets its share of threads (time only)
    recycle = {"max_tasks_per_child": WORKER_TASKS} if sys.version_info >= (3, 11) else {}
    pool = ProcessPoolExecutor(max_workers=n_procs, mp_context=get_context("spawn"), initializer=_share_cores,
                               initargs=(max(1, (os.cpu_count() or 1) // n_procs),), **recycle)
    pending: dict = {}
    procs: dict = {}  # the pool's worker processes, kept to read a dead one's exit code
    try:
        while queue or pending:
            broken = False
            while queue and len(pending) < n_workers and not broken:
                try:
                    pending[pool.submit(_run_one, fn, todo[queue[0]])] = queue[0]
                    queue.pop(0)
                except BrokenProcessPool:
                    broken = True
                procs.update(getattr(pool, "_processes", None) or {})
            if not broken:
                finished, _ = wait(pending, return_when=FIRST_COMPLETED)
                for fut in finished:
                    try:
                        result = fut.result()
                    except BrokenProcessPool:
                        broken = True
                        continue
                    finish(pending.pop(fut), result, False)
            if broken:  # a worker died: harvest what finished, report the rest as in flight
                wait(pending)  # a broken pool fails every pending future promptly
                in_flight = []
                for fut, k in pending.items():
                    try:
                        result = fut.result()
                    except BrokenProcessPool:
                        in_flight.append(k)
                        continue
                    finish(k, result, False)
                pool.shutdown(wait=True, cancel_futures=True)
                for proc in procs.values():
                    proc.join(timeout=5.0)
                codes = [proc.exitcode for proc in procs.values() if proc.exitcode not in (None, 0)]
                return [k for k in todo if k in in_flight], (codes[0] if codes else None)
    except BaseException:  # e.g. Ctrl-C: drop the queued tasks instead of running them to the end
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown(wait=True)
    return [], None


def _run_in_processes(fn, todo: dict, finish, n_workers: int) -> None:
    """Run ``todo`` in spawned worker processes; a dead worker costs its own task, not the run.

    When a worker dies (segfault, abort, OOM kill), the tasks that were in flight are run again one at a
    time, each in a fresh single-worker pool: the one that kills its worker again becomes a
    ``WorkerDied`` error result; the others, and every task not yet started, go on in a new pool.
    """
    remaining = dict(todo)

    def done(k: str, result: dict, cached: bool = False) -> None:
        remaining.pop(k, None)
        finish(k, result, cached)

    idle_breaks = 0
    while remaining:
        n_before = len(remaining)
        in_flight, code = _pool_round(fn, dict(remaining), done, n_workers)
        for k in in_flight:
            again, code = _pool_round(fn, {k: remaining[k]}, done, 1)
            if again:
                done(k, _dead_worker_result(code))
        idle_breaks = idle_breaks + 1 if len(remaining) == n_before else 0
        if idle_breaks >= 3:  # workers keep dying with no task running: give up on the rest, not forever
            for k in list(remaining):
                done(k, _dead_worker_result(code))


def _ray_module():
    try:
        import ray
    except ImportError:
        raise InputError("Ray is not installed: pip install -e '.[cluster]' (or run without --ray)") from None
    return ray


def start_local_ray(num_cpus: int) -> None:
    """Start a Ray head on this machine only (127.0.0.1, no dashboard) with ``num_cpus`` task slots.

    Its workers run at niceness 0, as local workers do: Ray's default (``worker_niceness`` 15) lets any other
    process on the machine starve them -- measured on 2 cores with two other trials running: one grasp trial
    took 198 s of wall time on a niceness-15 Ray worker against 37 s on a local worker (session 42)."""
    ray = _ray_module()
    ray.init(num_cpus=max(int(num_cpus), 1), include_dashboard=False, log_to_driver=False,
             _node_ip_address="127.0.0.1", _system_config={"worker_niceness": 0})


def _run_on_ray(fn, todo: dict, finish, address: str, n_workers: int) -> None:
    """Submit every todo task as a Ray remote call of ``_run_one(fn, spec)``; finish them as they complete."""
    ray = _ray_module()
    if not ray.is_initialized():
        if address == "local":
            start_local_ray(n_workers)
        else:
            ray.init(address=address, log_to_driver=False)
    remote = ray.remote(num_cpus=1)(_run_one)
    pending = {remote.remote(fn, s): k for k, s in todo.items()}
    while pending:
        ready, _ = ray.wait(list(pending), num_returns=1)
        for ref in ready:
            k = pending.pop(ref)
            try:
                result = ray.get(ref)
            except ray.exceptions.RayError as e:  # the worker died (after Ray's own retries): this task fails
                result = {"status": "error", "worker_died": True,
                          "error": one_line(e, limit=500)}
            finish(k, result, False)
