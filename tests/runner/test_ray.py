"""The same grasp trials through a local Ray head and through local workers give the same outcomes.

The head is started on this machine only (``runner.start_local_ray``: ``_node_ip_address="127.0.0.1"``,
no dashboard); Ray 2.60 still registers the node under the machine's own address (measured:
192.0.2.2 here), so the test checks that the cluster is this one machine. Its workers must run at
niceness 0: at Ray's default 15 any other process starves them (a trial 5x slower, session 42).
"""

from __future__ import annotations

import os
import socket

import pytest

from catgrasp_drake.runner import run_tasks, start_local_ray
from catgrasp_drake.station.handwritten import load_handwritten_motion
from catgrasp_drake.training import grasp_trial_task

ray = pytest.importorskip("ray", reason="Ray is the optional extra .[cluster]")


def _specs():
    out = []
    for instance in ("drill_00", "drill_05"):
        out.append({"task": "grasp_trial", "scenario": "drill_default", "category": "drill", "instance": instance,
                    "motion": load_handwritten_motion("drill", instance).to_dict()})
    return out


def _niceness() -> int:
    return os.nice(0)


def _outcome(result: dict) -> dict:
    return {k: v for k, v in result.items() if k not in ("wall_time_s", "plan_time_s", "realtime_rate")}


@pytest.mark.slow
def test_ray_trials_equal_local_trials(tmp_path):
    specs = _specs()
    local = run_tasks(grasp_trial_task, specs, cache_dir=tmp_path / "local", code_version="t", workers=2)
    try:
        start_local_ray(2)
        assert ray.get(ray.remote(num_cpus=1)(_niceness).remote()) == _niceness()  # as local workers run
        remote = run_tasks(grasp_trial_task, specs, cache_dir=tmp_path / "ray", code_version="t",
                           ray_address="local")
        assert ray.is_initialized()
        nodes = ray.nodes()
        assert len(nodes) == 1 and nodes[0]["NodeManagerHostname"] == socket.gethostname()
    finally:
        ray.shutdown()
    assert [_outcome(o.result) for o in remote] == [_outcome(o.result) for o in local]
    assert any(o.result["functional_success"] for o in remote)  # real trials, not errors
    assert not any(o.cached for o in remote)
