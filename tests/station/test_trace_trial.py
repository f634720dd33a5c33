"""PHYSICS: diagrams/trace_trial.py reads when a grasp goes wrong -- the hand-written mug grasp tilts mug_09
while the fingers close, before anything is lifted (docs/station.md, session 10: 20 deg, handle side 1.6 cm up)."""

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


@pytest.mark.slow
def test_the_mug_tilts_during_the_closing_not_the_hold(capsys):
    assert _trace_main()(["--category", "mug", "--instance", "mug_09", "--start", "close", "--stop", "lift",
                          "--every", "0.55"]) == 0
    rows = [line.split() for line in capsys.readouterr().out.splitlines() if re.match(r"\s*\d+\.\d+ ", line)]
    (t0, phase0, tilt0, *_), (t1, phase1, tilt1, rise1, *links) = rows[0], rows[-1]
    assert float(t1) - float(t0) == pytest.approx(1.1)  # the closing lasts 1.1 s: traced from its start to the lift
    assert phase0 == "close" and float(tilt0.rstrip("°")) < 1.0  # upright when the fingers start to close
    assert phase1 in ("close", "lift") and float(tilt1.rstrip("°")) > 15.0  # tilted before the lift
    assert 0.5 < float(rise1.rstrip("cm")) < 3.0 and links  # the handle side raised, in the hand


def test_a_nonpositive_interval_is_refused():
    with pytest.raises(SystemExit):
        _trace_main()(["--category", "mug", "--every", "0"])
