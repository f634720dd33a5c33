"""A film of one grasp trial: the station seen at the phases of the motion, one PNG strip.

``film_grasp(scenario, motion_O, path)`` runs a grasp trial (the motion given
in the object frame, planned around the true object) and
``film_transfer(td, path)`` runs a transfer diagram (perception, estimate,
prediction, plan); both stop at every instant of
:func:`catgrasp_drake.trial.phase_instants` (approach, reach, close, the
middle of the closing, lift, hold, shake, press, end) and render the scene
there from two cameras aimed at the object's starting place, so a person sees
at a glance where a grasp went wrong (pushed over on the way in, turned while
closing, slipped while shaken). Each tile is labelled with the phase, the
time, and the object's rise (cm) and tilt (deg) against its start (on the
first row; the others name their view); the title holds the verdict. The simulation is the same as without the film (the
plant's updates are periodic; a test checks the outcome).

Views (``FILM_VIEWS``): ``(name, azimuth_deg, elevation_deg)`` about the
object's starting position, azimuth measured in the world from the
direction of the arm's base seen from the object (so the arm does not hide
the hand: "left" and "right" see the grasp in profile; a view from above
is hidden by the forearm), 0.7 m away, aimed 10 cm above the object's base.

Close-up (``closeup=True``, ``catgrasp film --closeup``): the cameras
(``CLOSEUP_VIEWS``) follow the object's functional region (trigger, handle)
at ``CLOSEUP_DISTANCE_M``, with azimuths measured from the object's own +y
(its functional direction) at each frame: "front" looks back at the trigger
from the nozzle or chuck side, "side" from the object's -x side, "below" from
under the region -- or, where that would put it under the table (a small drill's trigger sits low), from as
low as :data:`CLOSEUP_MIN_HEIGHT_M` above the table top allows. Where the fingers meet the trigger or the
handle is seen at the scale of a finger (an index fingertip sliding off the side of a
spray-bottle trigger, say) -- which the station-scale views do not show.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

import numpy as np

from catgrasp_drake.core.visibility import camera_on_sphere_position
from catgrasp_drake.data.categories import FUNCTIONAL_REGION
from catgrasp_drake.errors import InputError
from catgrasp_drake.planning.records import PlanParams
from catgrasp_drake.station.builder import RENDERER_NAME, StationHandles
from catgrasp_drake.station.judge import tilt_deg
from catgrasp_drake.transfer import run_transfer
from catgrasp_drake.trial import run_grasp_trial, trial_diagram
from catgrasp_drake.viz.render import contact_sheet, render_color

#: (name, azimuth from the object-to-arm-base direction (deg), elevation (deg)).
FILM_VIEWS: tuple[tuple[str, float, float], ...] = (("left", 90.0, 15.0), ("right", -90.0, 15.0))
FILM_DISTANCE_M = 0.7
FILM_TARGET_HEIGHT_M = 0.10
FILM_FOV_DEG = 45.0
#: Size (w, h) of one frame, pixels.
FILM_TILE = (180, 180)
#: Close-up views (name, azimuth from the object's +y about the world vertical (deg), elevation (deg)),
#: their distance (m) from the functional region's centre, and the frame size.
CLOSEUP_VIEWS: tuple[tuple[str, float, float], ...] = (("front", 0.0, 10.0), ("side", 90.0, 10.0),
                                                       ("below", 0.0, -40.0))
CLOSEUP_DISTANCE_M = 0.22
CLOSEUP_FOV_DEG = 50.0
CLOSEUP_TILE = (300, 300)
#: A camera is kept at least this far (m) above the table top: under it, it sees only the table.
CLOSEUP_MIN_HEIGHT_M = 0.01


def elevation_above(target, distance: float, elevation: float, floor_z: float) -> float:
    """``elevation`` (rad), raised just enough that a camera ``distance`` (m) from ``target`` (world, m) at that
    elevation is at least at height ``floor_z`` (m); at most 80 deg (a camera straight above has no "up")."""
    lowest = (floor_z - float(target[2])) / distance
    return elevation if lowest <= -1.0 else max(elevation, math.asin(min(lowest, math.sin(math.radians(80.0)))))


def verdict_word(grasp_success: bool, functional_success: bool) -> str:
    """"functional", "grasped" (held, the function missed) or "failed"."""
    return "functional" if functional_success else "grasped" if grasp_success else "failed"


@dataclass
class Film:
    """Collects the frames of one trial: ``film(label, root_context)`` renders every view.

    ``closeup_O`` (3,) a point in the object frame O (m): the views then follow it (close-up, module
    docstring) instead of looking at the object's starting place."""

    station: StationHandles
    size: tuple[int, int] = FILM_TILE
    views: tuple[tuple[str, float, float], ...] = FILM_VIEWS
    closeup_O: np.ndarray | None = None
    frames: list = field(default_factory=list)  # (label, t, rise_m, tilt_deg, [image per view])
    _X_WO0: np.ndarray | None = field(default=None, init=False, repr=False)  # the object's pose in frame 0

    def __call__(self, label: str, context) -> None:
        h = self.station
        plant_ctx = h.plant.GetMyContextFromRoot(context)
        X_WO = h.plant.EvalBodyPoseInWorld(plant_ctx, h.object_body).GetAsMatrix4()
        if self._X_WO0 is None:
            self._X_WO0 = X_WO
        X0 = self._X_WO0
        rise = float(X_WO[2, 3] - X0[2, 3])
        query = h.scene_graph.get_query_output_port().Eval(h.scene_graph.GetMyContextFromRoot(context))
        if self.closeup_O is None:
            target = X0[:3, 3] + np.array([0.0, 0.0, FILM_TARGET_HEIGHT_M])
            to_arm = h.scenario.arm_base.matrix()[:3, 3] - X0[:3, 3]
            yaw0, distance, fov = math.atan2(to_arm[1], to_arm[0]), FILM_DISTANCE_M, FILM_FOV_DEG
        else:  # follow the region, azimuths from the object's +y as it is now
            target = X_WO[:3, :3] @ np.asarray(self.closeup_O, float) + X_WO[:3, 3]
            yaw0, distance, fov = math.atan2(X_WO[1, 1], X_WO[0, 1]), CLOSEUP_DISTANCE_M, CLOSEUP_FOV_DEG
        images = []
        table_z = float(h.scenario.table.pose.matrix()[2, 3])
        for _, az, el in self.views:
            el = elevation_above(target, distance, math.radians(el), table_z + CLOSEUP_MIN_HEIGHT_M)
            eye = camera_on_sphere_position(target, distance, yaw0 + math.radians(az), el)
            images.append(render_color(query, h.scene_graph.world_frame_id(), eye, target, self.size, fov,
                                       renderer=RENDERER_NAME))
        self.frames.append((label, float(context.get_time()), rise, tilt_deg(X0, X_WO), images))

    def write(self, path: str | os.PathLike, title: str) -> None:
        """One PNG: a column per phase, a row per view (atomic write)."""
        if not self.frames:
            raise InputError("film: no frames (the plan failed before the motion started?)")
        images, labels = [], []
        for v, (name, _, _) in enumerate(self.views):
            for label, t, rise, tilt, frame in self.frames:
                images.append(frame[v])
                labels.append(f"{label} {t:.1f}s {100 * rise:+.1f}cm {tilt:.0f}deg" if v == 0 else f"{name} view")
        contact_sheet(images, labels, path, columns=len(self.frames), title=title)


def _title(what: str, result) -> str:
    verdict = verdict_word(result.grasp_success, result.functional_success)
    verdict = "grasped, not functional" if verdict == "grasped" else verdict
    reason = f" ({result.failure_reason}: {result.detail})" if result.failure_reason else ""
    return f"{what}: {verdict}{reason}"[:240]


def _film_for(station: StationHandles, closeup: bool, size) -> Film:
    """A :class:`Film` of ``station``: the station-scale views, or ``closeup`` views that follow the object's
    functional region (InputError when the object has none annotated)."""
    if not closeup:
        return Film(station, size=size or FILM_TILE)
    obj = station.scenario.object
    name = FUNCTIONAL_REGION.get(obj.category or "")
    region = obj.annotations().get("regions", {}).get(name) if name else None
    if region is None:
        raise InputError(f"close-up: {obj.instance or station.scenario.name} has no annotated functional region "
                         f"({name or 'unknown category'}) to follow")
    return Film(station, size=size or CLOSEUP_TILE, views=CLOSEUP_VIEWS,
                closeup_O=np.asarray(region["center"], float))


def film_grasp(scenario, motion_O, path: str | os.PathLike, *, size: tuple[int, int] | None = None,
               params: PlanParams = PlanParams(), closeup: bool = False):
    """Run ``motion_O`` (object frame) as :func:`catgrasp_drake.trial.run_grasp_trial` does, film it into
    ``path`` (PNG) and return the :class:`~catgrasp_drake.trial.TrialResult`. A plan that fails writes
    the start frame only, titled with the planner's reason. ``closeup``: views that follow the functional
    region (module docstring); ``size`` of a frame (pixels; default by the views)."""
    td = trial_diagram(scenario)  # the diagram run_grasp_trial runs (cached per scenario)
    film = _film_for(td.station, closeup, size)
    result = run_grasp_trial(scenario, motion_O, params=params, on_phase=film)
    name = f"{scenario.object.category or ''} {scenario.object.instance or scenario.name}".strip()
    if not film.frames:
        film("start (no motion)", td.diagram.CreateDefaultContext())
    film.write(path, _title(name, result))
    return result


def film_transfer(td, path: str | os.PathLike, *, size: tuple[int, int] | None = None, title: str = "",
                  closeup: bool = False):
    """Run the transfer diagram ``td`` (:func:`catgrasp_drake.transfer.run_transfer`), film it into ``path``
    (PNG) and return the :class:`~catgrasp_drake.transfer.TransferResult` (``closeup``, ``size``: as
    :func:`film_grasp`)."""
    film = _film_for(td.station, closeup, size)
    result = run_transfer(td, on_phase=film)
    if not film.frames:
        film("start (no motion)", td.diagram.CreateDefaultContext())
    film.write(path, _title(title or f"{td.model.category} {td.station.scenario.object.instance}", result))
    return result
