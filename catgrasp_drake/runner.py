"""Run many independent tasks (grasp trials) in parallel with an on-disk cache.

Training and evaluation are made of independent trials. This module runs a
pure task function over JSON-able task specs in worker processes and stores
every finished result as its own small JSON file, written atomically, named by
the hash of (task spec, code fingerprint). Hence:

* re-running never recomputes what is already known (same spec, same code);
* a run killed at any moment (even ``kill -9``) resumes without losing or
  double-counting a finished task: a result file either exists whole or not;
* a task that raises becomes a result ``{"status": "error", "error": ...}``
  rather than a dead run.

The task function must be a module-level callable (importable by workers)
taking the spec dict and returning a JSON-able dict.
"""

from __future__ import annotations

import hashlib
import json
import os
import traceback
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import dataclass
from multiprocessing import get_context
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping, Sequence

from catgrasp_drake.core.fileio import atomic_write_text
from catgrasp_drake.errors import InputError

_PACKAGE_ROOT = Path(__file__).resolve().parent


def canonical_json(obj: Any) -> str:
    """Deterministic JSON text (sorted keys, no spaces) used for hashing."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), allow_nan=False)


def code_fingerprint(paths: Sequence[str | os.PathLike]) -> str:
    """sha256 over the contents of the given files/directories (recursively, sorted).

    Used as the "code version" of a cache: change any file that can change a
    trial's outcome and the cached results are no longer reused.
    """
    h = hashlib.sha256()
    for root in paths:
        root = Path(root)
        files = sorted(p for p in root.rglob("*") if p.is_file()) if root.is_dir() else [root]
        for p in files:
            if p.suffix in (".pyc",) or "__pycache__" in p.parts:
                continue
            h.update(str(p.relative_to(root.parent)).encode())
            h.update(p.read_bytes())
    return h.hexdigest()[:16]


def task_key(spec: Mapping[str, Any], code_version: str) -> str:
    return hashlib.sha256((code_version + canonical_json(spec)).encode()).hexdigest()[:24]


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
        return result
    except Exception as e:  # a failed trial is an outcome, not a dead run
        return {
            "status": "error",
            "error": f"{type(e).__name__}: {e}".splitlines()[0][:500],
            "traceback": traceback.format_exc(limit=5)[-2000:],
        }


class TaskCache:
    """A directory of ``<key>.json`` result files."""

    def __init__(self, directory: str | os.PathLike, code_version: str):
        self.directory = Path(directory)
        self.code_version = code_version
        self.directory.mkdir(parents=True, exist_ok=True)

    def path(self, key: str) -> Path:
        return self.directory / f"{key}.json"

    def get(self, key: str) -> dict | None:
        p = self.path(key)
        try:
            record = json.loads(p.read_text())
        except FileNotFoundError:
            return None
        except (OSError, json.JSONDecodeError):
            return None  # unreadable: recompute (and overwrite atomically)
        if record.get("code_version") != self.code_version:
            return None
        return record.get("result")

    def put(self, key: str, spec: dict, result: dict) -> None:
        record = {"key": key, "code_version": self.code_version, "spec": spec, "result": result}
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
        if cache and not cached:
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
        with ProcessPoolExecutor(max_workers=min(n_workers, len(todo)), mp_context=get_context("spawn")) as pool:
            pending = {pool.submit(_run_one, fn, s): k for k, s in todo.items()}
            while pending:
                finished, _ = wait(pending, return_when=FIRST_COMPLETED)
                for fut in finished:
                    k = pending.pop(fut)
                    finish(k, fut.result(), False)
    return [TaskOutcome(k, spec_of[k], *results[k]) for k in keys]


def _ray_module():
    try:
        import ray
    except ImportError:
        raise InputError("Ray is not installed: pip install -e '.[cluster]' (or run without --ray)") from None
    return ray


def _run_on_ray(fn, todo: dict, finish, address: str, n_workers: int) -> None:
    """Submit every todo task as a Ray remote call of ``_run_one(fn, spec)``; finish them as they complete."""
    ray = _ray_module()
    if not ray.is_initialized():
        if address == "local":
            ray.init(num_cpus=max(n_workers, 1), include_dashboard=False, log_to_driver=False,
                     _node_ip_address="127.0.0.1")
        else:
            ray.init(address=address, log_to_driver=False)
    remote = ray.remote(num_cpus=1)(_run_one)
    pending = {remote.remote(fn, s): k for k, s in todo.items()}
    while pending:
        ready, _ = ray.wait(list(pending), num_returns=1)
        for ref in ready:
            k = pending.pop(ref)
            finish(k, ray.get(ref), False)
