"""The film of a trial: frames at the phases of the motion, and the same outcome as without it."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from catgrasp_drake.film import FILM_VIEWS, film_grasp
from catgrasp_drake.station.handwritten import load_handwritten_motion, shifted_motion
from catgrasp_drake.station.scenario import load_scenario, with_instance
from catgrasp_drake.trial import phase_instants, run_grasp_trial


def test_phase_instants_follow_the_timeline_and_add_the_middle_of_the_closing():
    from catgrasp_drake.planning.records import Timeline

    tl = Timeline(settle=0.0, approach=0.1, reach=2.0, close=2.8, lift=3.9, hold=4.9, shake=7.0, press=8.0, end=8.5)
    labels = [label for label, _ in phase_instants(tl)]
    assert labels == ["approach", "reach", "close", "closing", "lift", "hold", "shake", "press", "end"]
    assert dict(phase_instants(tl))["closing"] == (2.8 + 3.9) / 2


@pytest.fixture(scope="module")
def drill_00_trial():
    """The hand-written grasp on drill_00 (its default scenario), run once without a film:
    (scenario, motion, result), the reference both film tests compare against."""
    scenario = with_instance(load_scenario("drill_default"), "drill_00")
    motion = load_handwritten_motion("drill", "drill_00")
    return scenario, motion, run_grasp_trial(scenario, motion)


@pytest.mark.slow
def test_a_film_shows_every_phase_in_every_view_and_does_not_change_the_trial(tmp_path, drill_00_trial):
    scenario, motion, plain = drill_00_trial
    path = tmp_path / "film.png"
    filmed = film_grasp(scenario, motion, path, size=(64, 48))
    assert filmed.outcome() == plain.outcome()  # stopping to render changes nothing
    assert filmed.functional_success  # the hand-written drill grasp (tests/station/test_handwritten_physics.py)
    image = np.asarray(Image.open(path))
    columns = 1 + len(phase_instants_of(scenario, motion))  # the start, then every phase
    assert image.shape[1] == columns * 64
    assert image.shape[0] > len(FILM_VIEWS) * 48
    # the frames differ: the arm moves between the start and the end
    start, end = image[24:24 + 48, :64], image[24:24 + 48, -64:]
    assert np.abs(start.astype(int) - end.astype(int)).mean() > 5


def phase_instants_of(scenario, motion):
    from catgrasp_drake.trial import plan_for, trial_diagram

    return phase_instants(plan_for(trial_diagram(scenario), motion.in_world(scenario.X_WO())).timeline)


def test_a_grasp_that_cannot_be_planned_films_its_start_and_says_why(tmp_path):
    scenario = with_instance(load_scenario("drill_default"), "drill_00")
    motion = shifted_motion(load_handwritten_motion("drill", "drill_00"), "drill", "drill_00", (0.0, 0.0, 3.0))
    path = tmp_path / "film.png"
    result = film_grasp(scenario, motion, path, size=(64, 48))
    assert not result.grasp_success and result.plan_status != "ok"
    assert np.asarray(Image.open(path)).shape[1] == 64  # one frame: the start


@pytest.mark.slow
def test_a_closeup_follows_the_functional_region_and_does_not_change_the_trial(tmp_path, drill_00_trial):
    """``closeup=True``: one row per close-up view (front, side, below the trigger), and the same outcome."""
    from catgrasp_drake.film import CLOSEUP_VIEWS

    scenario, motion, plain = drill_00_trial
    path = tmp_path / "closeup.png"
    filmed = film_grasp(scenario, motion, path, size=(64, 48), closeup=True)
    assert filmed.outcome() == plain.outcome()
    image = np.asarray(Image.open(path))
    assert image.shape[1] == (1 + len(phase_instants_of(scenario, motion))) * 64
    assert image.shape[0] > len(CLOSEUP_VIEWS) * 48
    assert image.shape[0] < (len(CLOSEUP_VIEWS) + 1) * (48 + 24)  # three rows, not the station's two + one


def test_a_closeup_of_an_object_without_a_functional_region_says_so(tmp_path):
    import pytest

    from catgrasp_drake.errors import InputError
    from catgrasp_drake.film import _film_for
    from catgrasp_drake.trial import trial_diagram

    station = trial_diagram(load_scenario("cylinder_test")).station
    with pytest.raises(InputError, match="no annotated functional region"):
        _film_for(station, True, None)


def test_elevation_above_keeps_a_camera_over_the_table():
    import math

    from catgrasp_drake.film import elevation_above

    below = math.radians(-40.0)
    # 0.3 m up, 0.22 m away: -40 deg puts the camera at 0.159 m, above a floor at 0.01 m: unchanged
    assert elevation_above((0.0, 0.0, 0.3), 0.22, below, 0.01) == below
    # 0.08 m up: -40 deg would be at -0.061 m; raised to the floor exactly
    el = elevation_above((0.0, 0.0, 0.08), 0.22, below, 0.01)
    assert math.isclose(0.08 + 0.22 * math.sin(el), 0.01, abs_tol=1e-12)
    # a target under the floor: at most 80 deg up (a camera straight above has no "up" direction)
    assert math.isclose(elevation_above((0.0, 0.0, -1.0), 0.22, below, 0.01), math.radians(80.0))


def test_the_closeup_below_view_of_a_low_trigger_sees_the_trigger_not_the_table(tmp_path):
    """A small drill's trigger sits so low that a camera 40 deg under it would be inside the table."""
    from catgrasp_drake.data.stretch import STRESS_FAMILIES, stretch_instance
    from catgrasp_drake.film import CLOSEUP_VIEWS, _film_for
    from catgrasp_drake.station.handwritten import handwritten_trial
    from catgrasp_drake.trial import trial_diagram

    obj = stretch_instance("drill", "drill_08", STRESS_FAMILIES["small"], tmp_path)
    scenario, _ = handwritten_trial(object_dir=obj.directory)
    td = trial_diagram(scenario)
    film = _film_for(td.station, True, (64, 48))
    film("start", td.diagram.CreateDefaultContext())
    below = np.asarray(film.frames[0][4][[name for name, _, _ in CLOSEUP_VIEWS].index("below")], float)
    # the old camera, inside the table, saw one uniform colour (the table); now the drill and the sky behind it
    assert below[..., :3].reshape(-1, 3).std(axis=0).max() > 10.0
