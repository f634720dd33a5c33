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
