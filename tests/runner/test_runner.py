"""The parallel task runner: cache, resume after kill -9, errors as outcomes."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from catgrasp_drake.errors import InputError
from catgrasp_drake.runner import code_fingerprint, run_tasks


def square(spec: dict) -> dict:
    """A module-level task for worker processes."""
    if spec["x"] < 0:
        raise ValueError("negative input")
    time.sleep(spec.get("sleep", 0.0))
    return {"y": spec["x"] ** 2}


def core_threads(spec: dict) -> dict:
    """A task reporting the numerical core's thread count in its worker."""
    from catgrasp_drake.core.threads import n_threads

    time.sleep(0.2)  # both workers start
    return {"threads": n_threads()}


def test_worker_processes_share_the_cores_between_their_threads(tmp_path, monkeypatch):
    """Two worker processes on this machine: each one's numerical core runs at most cores // 2 threads
    (the fits' side-by-side threads would otherwise fight the sibling process for the cores); the
    environment variable caps it in this process too."""
    from catgrasp_drake.core.threads import THREADS_ENV, n_threads

    out = run_tasks(core_threads, [{"i": i} for i in range(2)], cache_dir=None, code_version="v", workers=2)
    assert {o.result["threads"] for o in out} == {max(1, min(n_threads(), (os.cpu_count() or 1) // 2))}
    monkeypatch.setenv(THREADS_ENV, "1")
    assert n_threads() == 1


def worker_pid(spec: dict) -> dict:
    """A task reporting its worker process."""
    time.sleep(0.05)
    return {"pid": os.getpid()}


@pytest.mark.skipif(sys.version_info < (3, 11), reason="ProcessPoolExecutor(max_tasks_per_child=) needs 3.11")
def test_a_worker_process_is_replaced_after_its_share_of_tasks(monkeypatch):
    """Workers are recycled every WORKER_TASKS tasks (Drake's Python systems are never freed, so a long-lived
    worker only grows): 2 workers, at most 2 tasks each, 8 tasks -> at least 4 processes. A process may run
    fewer: when the queue empties, the last tasks go to whichever live workers take them (CI saw 2,2,2,1,1)."""
    import collections

    from catgrasp_drake import runner

    monkeypatch.setattr(runner, "WORKER_TASKS", 2)
    out = run_tasks(worker_pid, [{"i": i} for i in range(8)], cache_dir=None, code_version="v", workers=2)
    per_process = collections.Counter(o.result["pid"] for o in out)
    assert sum(per_process.values()) == 8
    assert max(per_process.values()) == 2
    assert len(per_process) >= 4
    assert os.getpid() not in per_process


def test_python_leaf_systems_outlive_their_diagram_in_this_drake():
    """Why WORKER_TASKS exists, checked against the installed Drake (a canary, session 35): a Python-defined
    LeafSystem with no ports or callbacks at all, added to a DiagramBuilder and built into a diagram, is never
    freed. The builder and the system name each other in ``_pydrake_internal_ref_cycle_peers``, and the
    builder's C++ side holds the Python system too, a reference the collector cannot see. So no rewrite of
    our systems' callbacks can free them. If this fails, Drake has fixed it: drop the recycling, and
    measure a long ``--workers 0`` run's memory to confirm."""
    import gc
    import weakref

    from pydrake.systems.framework import DiagramBuilder, LeafSystem

    class Empty(LeafSystem):
        pass

    alive = []
    for _ in range(3):
        builder = DiagramBuilder()
        alive.append(weakref.ref(builder.AddSystem(Empty())))
        diagram = builder.Build()
        del builder, diagram
    gc.collect()
    assert sum(ref() is not None for ref in alive) == 3


def test_runs_in_processes_in_spec_order_and_caches(tmp_path):
    specs = [{"x": i} for i in range(6)]
    out = run_tasks(square, specs, cache_dir=tmp_path, code_version="v1", workers=2)
    assert [o.result["y"] for o in out] == [i * i for i in range(6)]
    assert not any(o.cached for o in out)
    again = run_tasks(square, specs, cache_dir=tmp_path, code_version="v1", workers=2)
    assert all(o.cached for o in again) and [o.result for o in again] == [o.result for o in out]
    # a new code version recomputes
    fresh = run_tasks(square, specs[:2], cache_dir=tmp_path, code_version="v2", workers=0)
    assert not any(o.cached for o in fresh)


def test_a_failing_task_is_an_outcome_not_a_dead_run(tmp_path):
    out = run_tasks(square, [{"x": -1}, {"x": 3}], cache_dir=None, code_version="v", workers=0)
    assert out[0].result["status"] == "error" and "negative input" in out[0].result["error"]
    assert out[1].result == {"y": 9, "status": "ok"}


def test_duplicates_run_once_and_progress_counts(tmp_path):
    seen = []
    out = run_tasks(square, [{"x": 2}, {"x": 2}, {"x": 3}], cache_dir=tmp_path, code_version="v",
                    workers=0, progress=lambda o, d, t: seen.append((d, t)))
    assert len(out) == 3 and seen == [(1, 2), (2, 2)]
    assert len(list(tmp_path.glob("*.json"))) == 2


def test_bad_spec_is_a_clear_error():
    with pytest.raises(InputError, match="JSON-able"):
        run_tasks(square, [{"x": object()}], cache_dir=None, code_version="v", workers=0)


def test_code_fingerprint_tracks_file_contents(tmp_path):
    (tmp_path / "a.py").write_text("x = 1\n")
    f1 = code_fingerprint([tmp_path])
    (tmp_path / "a.py").write_text("x = 2\n")
    assert code_fingerprint([tmp_path]) != f1


def test_code_fingerprint_follows_contents_not_locations(tmp_path):
    """Moving a module (unedited) or the whole tree keeps the fingerprint; renaming a data file does not."""
    for where in ("one", "two"):
        (tmp_path / where / "pkg").mkdir(parents=True)
        (tmp_path / where / "data").mkdir()
    (tmp_path / "one" / "pkg" / "a.py").write_text("def f():\n    return 1\n")
    (tmp_path / "one" / "data" / "drill_00.obj").write_text("v 0 0 0\n")
    f1 = code_fingerprint([tmp_path / "one" / "pkg", tmp_path / "one" / "data"])
    (tmp_path / "one" / "pkg" / "sub").mkdir()
    (tmp_path / "one" / "pkg" / "a.py").rename(tmp_path / "one" / "pkg" / "sub" / "b.py")
    assert code_fingerprint([tmp_path / "one" / "data", tmp_path / "one" / "pkg"]) == f1  # moved, any order
    (tmp_path / "two" / "pkg" / "b.py").write_text("def f():\n    return 1\n")
    (tmp_path / "two" / "data" / "drill_00.obj").write_text("v 0 0 0\n")
    assert code_fingerprint([tmp_path / "two" / "pkg", tmp_path / "two" / "data"]) == f1  # another location
    (tmp_path / "two" / "data" / "drill_00.obj").rename(tmp_path / "two" / "data" / "drill_01.obj")
    assert code_fingerprint([tmp_path / "two" / "pkg", tmp_path / "two" / "data"]) != f1  # data names matter


def test_trial_cache_key_ignores_the_offline_tools():
    from catgrasp_drake.trial import TRIAL_CODE_PATHS

    repo = Path(__file__).resolve().parents[2]
    listed = [Path(p).resolve() for p in TRIAL_CODE_PATHS]
    assert all(p.exists() for p in listed), [p for p in listed if not p.exists()]
    tools = (repo / "tools").resolve()
    assert not any(p == tools or tools in p.parents or p in tools.parents for p in listed)


_SCRIPT = """
import sys, json
sys.path.insert(0, {tests!r})
from runner.test_runner import square
from catgrasp_drake.runner import run_tasks
specs = [{{"x": i, "sleep": 0.2}} for i in range(12)]
out = run_tasks(square, specs, cache_dir={cache!r}, code_version="v", workers=0,
                progress=lambda o, d, t: print("done", d, flush=True))
print(json.dumps([o.result["y"] for o in out]))
"""


def test_kill_minus_9_then_resume_loses_nothing(tmp_path):
    cache = tmp_path / "cache"
    script = _SCRIPT.format(tests=str(Path(__file__).resolve().parents[1]), cache=str(cache))
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    for _ in range(4):  # let four tasks finish, then kill hard mid-task
        assert proc.stdout.readline().startswith("done")
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    finished = list(cache.glob("*.json"))
    assert 4 <= len(finished) < 12
    assert not list(cache.glob(".*.tmp"))  # no half-written file
    for f in finished:
        json.loads(f.read_text())
    res = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True)
    lines = res.stdout.strip().splitlines()
    assert json.loads(lines[-1]) == [i * i for i in range(12)]
    assert len(list(cache.glob("*.json"))) == 12
