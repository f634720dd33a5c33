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


def pytest_collection_modifyitems(session, config, items):
    """Files with a ``slow`` test first, every file's tests kept together and in order.

    ``pytest -n auto --dist loadfile`` hands files to its workers in collection order: with the slow
    (simulating) files last, as the directory order puts the training tests, one worker ran a 3-minute
    file alone while the other had finished. Slow files first, the fast ones fill the gaps at the end.
    """
    slow_files = {item.path for item in items if item.get_closest_marker("slow") is not None}
    items.sort(key=lambda item: item.path not in slow_files)  # stable: the order within each group is kept
