"""Shared test fixtures: locations of the repository and of ../shared."""

from __future__ import annotations

from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"
AIS_DRILLS = SHARED / "datasets" / "ais_drills"
# the spray grasp of sessions 17-39, pinned for tests whose known answers are its misfits (deep and large bottles)
S17_SPRAY_GRASP = REPO / "tests" / "fixtures" / "spray_bottle_grasp_s17.yaml"


@pytest.fixture(scope="session")
def ais_drill_paths():
    """The 11 real drill clouds from ../shared, or skip when ../shared is absent."""
    paths = sorted(AIS_DRILLS.glob("drill_*.pcd"))
    if not paths:
        pytest.skip("../shared/datasets/ais_drills not present")
    return paths
