"""PHYSICS: diagrams/trace_trial.py reads when a grasp goes wrong, and when it no longer does.

Known answers (docs/station.md): until session 11 the hand-written mug grasp tilted mug_09 by 20 deg while
the fingers closed (the little finger, curled to 0.856 rad, lifted the handle from below). With the little
finger closed to 0.65 rad the mug stays upright through the closing. Until session 12 the short mug_06
(7.1 cm) swung down during the lift: the table clearance kept the hand 3 cm up and only the ring finger and
thumb held its handle. With the hand turned 30 deg about the mug's x axis (coming down on the handle) the
index, middle and ring fingers and the thumb hold it and it stays upright.
"""

from __future__ import annotations

import importlib.util
import re

import pytest

from tests.conftest import REPO

pytest.importorskip("pydrake")


def _trace_main():
    spec = importlib.util.spec_from_file_location("trace_trial", REPO / "diagrams" / "trace_trial.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.main


def _trace(capsys, *args) -> tuple[list[list[str]], str]:
    assert _trace_main()(["--category", "mug", *args]) == 0
    out = capsys.readouterr().out.splitlines()
    rows = [line.split() for line in out if re.match(r"\s*\d+\.\d+ ", line)]
    return rows, out[-1]


def _deg(cell: str) -> float:
    return float(cell.rstrip("°"))


@pytest.mark.slow
def test_the_mug_stays_upright_while_the_fingers_close(capsys):
    rows, verdict = _trace(capsys, "--instance", "mug_09", "--start", "close", "--stop", "lift", "--every", "0.55")
    (t0, phase0, tilt0, *_), (t1, phase1, tilt1, _rise, *links) = rows[0], rows[-1]
    assert float(t1) - float(t0) == pytest.approx(1.1)  # the closing lasts 1.1 s: traced from its start to the lift
    assert phase0 == "close" and _deg(tilt0) < 1.0
    assert phase1 in ("close", "lift") and _deg(tilt1) < 5.0  # session 10's grasp: 20.1 deg here
    links = {link.rstrip(",") for link in links}
    assert {"index_distal", "thumb_middle"} <= links  # index on top of the handle, the thumb opposite
    assert verdict.startswith("mug_09: functional")


@pytest.mark.slow
def test_a_short_mug_is_held_upright_through_the_lift(capsys):
    rows, verdict = _trace(capsys, "--instance", "mug_06", "--start", "lift", "--stop", "hold", "--every", "0.5")
    (_, phase0, tilt0, *_), (_, _, tilt1, _rise, *links) = rows[0], rows[-1]
    assert phase0 == "lift" and _deg(tilt0) < 2.0  # upright when the lift starts ...
    assert _deg(tilt1) < 15.0  # ... and still when it is up (session 11's grasp: 30 deg)
    assert "index_distal" in {link.rstrip(",") for link in links}  # the index reaches the low handle
    assert verdict.startswith("mug_06: functional")


def test_a_nonpositive_interval_is_refused():
    with pytest.raises(SystemExit):
        _trace_main()(["--category", "mug", "--every", "0"])


def test_without_a_category_or_an_object_it_says_what_to_give():
    with pytest.raises(SystemExit):
        _trace_main()([])


def test_an_object_directory_that_is_not_an_imported_object_is_named(tmp_path):
    from catgrasp_drake.errors import ModelFileError

    with pytest.raises(ModelFileError, match="no such object directory"):
        _trace_main()(["--object", str(tmp_path / "nothing_here")])


def test_the_shift_moves_the_grasp(capsys):
    """Moved 3 m up, the hand-written drill grasp cannot be planned: the trace says so before any simulation."""
    assert _trace_main()(["--category", "drill", "--shift", "0", "0", "3"]) == 1
    assert "plan refused" in capsys.readouterr().out
