"""Interactive Meshcat view of a trained category model's latent shape space.

:class:`ShapeViewer` draws, in one Meshcat scene whose world frame is the
category's canonical object frame O (z up, base on z = 0, metres):

================================  =============================================================
path                              content
================================  =============================================================
``/view/shape``                   the completed shape ``C + G W(x)`` for the current latent x
``/view/grasp/pregrasp``          triad: pregrasp pose of the hand base link, ``R(x)`` warped by W(x)
``/view/grasp/grasp``             triad: grasp pose of the hand base link (same)
``/view/hand/<body>``             the SVH hand's geometry at the grasp pose, in its "preshape"
``/view/canonical``               the canonical shape C (hidden; toggle it in the controls)
``/view/instance/<name>``         the selected training instance's CPD registration ``C + G W_i``
                                  (hidden; its path names the instance)
================================  =============================================================

Controls: one slider per latent dimension (``x1`` ... ``xq``; whitened
coordinates, so about +-3 spans the N(0, I) prior) and a slider ``instance``
(0 ... K-1) that jumps to a training instance's latent vector. Meshcat sends
control values back to this process; :meth:`ShapeViewer.poll` reads them and
redraws when something changed (call it in a loop).

:meth:`ShapeViewer.export_html` writes a self-contained HTML page (no
controls: ``StaticHtml`` cannot run sliders) in which every training
instance's completed shape, grasp triads and hand live under their own
toggleable path ``/view/instances/<name>``; all but the first are hidden.
"""

from __future__ import annotations

import logging
import math
import os

import numpy as np
from pydrake.geometry import Meshcat, Rgba
from pydrake.math import RigidTransform
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.systems.framework import DiagramBuilder

from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.errors import InputError
from catgrasp_drake.grasping.motion import GraspMotion
from catgrasp_drake.robot import models
from catgrasp_drake.viz.meshcat_tools import COLORS, draw_cloud, draw_triad, save_static_html, start_meshcat

ROOT = "/view"
INSTANCE_SLIDER = "instance"
#: Latent sliders' resolution (whitened units).
SLIDER_STEP = 0.01
#: The hand posture shown at the grasp pose (the hand arrives there in it, then closes).
HAND_POSTURE = "preshape"
_REGISTERED_COLOR = Rgba(0.55, 0.55, 0.6, 1.0)
_HAND_OPACITY = 0.6
_HAND_COLOR = Rgba(0.6, 0.6, 0.65, 1.0)


def latent_slider_names(q: int) -> list[str]:
    """Names of the latent sliders: ``x1`` ... ``xq``."""
    return [f"x{j + 1}" for j in range(q)]


def _quiet_meshcat() -> Meshcat:
    """A localhost Meshcat for off-screen use, without Drake logging its (never visited) URL."""
    logger = logging.getLogger("drake")
    level = logger.level
    logger.setLevel(max(level, logging.WARNING))
    try:
        return start_meshcat()
    finally:
        logger.setLevel(level)


def _aim_camera(meshcat: Meshcat, points_O: np.ndarray) -> None:
    """Look at the centre of ``points_O`` (object frame = Meshcat world) from the front-right, above."""
    center = points_O.mean(axis=0)
    extent = float(np.ptp(points_O, axis=0).max())
    meshcat.SetCameraPose(center + np.array([2.0, -2.0, 1.2]) * extent, center)


class _HandDrawer:
    """The SVH hand's illustration geometry (primitives) posed in Meshcat without a simulator.

    A continuous MultibodyPlant holds only the floating hand; setting its base
    pose ``X_OH`` and joint angles gives every hand body's pose in O, which is
    sent to Meshcat as one transform per body.
    """

    def __init__(self):
        self._models = models
        builder = DiagramBuilder()
        plant, scene_graph = AddMultibodyPlantSceneGraph(builder, 0.0)
        self._hand = models.add_hand(plant)
        plant.Finalize()
        self._plant = plant
        self._context = plant.CreateDefaultContext()
        self._base = plant.GetBodyByName(models.HAND_BASE_LINK, self._hand)
        self._bodies = [plant.get_body(i) for i in plant.GetBodyIndices(self._hand)]
        inspector = scene_graph.model_inspector()
        self._geometry = {}  # body name -> [(X_BG, shape, rgba)]
        for body in self._bodies:
            items = []
            for gid in plant.GetVisualGeometriesForBody(body):
                props = inspector.GetIllustrationProperties(gid)
                c = props.GetPropertyOrDefault("phong", "diffuse", _HAND_COLOR) if props else _HAND_COLOR
                rgba = Rgba(c.r(), c.g(), c.b(), _HAND_OPACITY)
                items.append((inspector.GetPoseInFrame(gid), inspector.GetShape(gid), rgba))
            self._geometry[body.name()] = items

    def add(self, meshcat: Meshcat, path: str) -> None:
        """Create the hand's geometry under ``path`` (one child path per body)."""
        for body, items in self._geometry.items():
            for j, (X_BG, shape, rgba) in enumerate(items):
                meshcat.SetObject(f"{path}/{body}/{j}", shape, rgba)
                meshcat.SetTransform(f"{path}/{body}/{j}", X_BG)

    def body_poses(self, X_OH: np.ndarray, posture: np.ndarray) -> dict[str, RigidTransform]:
        """Pose in O of every hand body for the base link at ``X_OH`` (4x4) and a (9,) posture (rad)."""
        self._models.set_hand_angles(self._plant, self._context, self._hand, np.asarray(posture, float))
        self._plant.SetFreeBodyPose(self._context, self._base, RigidTransform(np.asarray(X_OH, float)))
        return {b.name(): self._plant.EvalBodyPoseInWorld(self._context, b) for b in self._bodies}

    def pose(self, meshcat: Meshcat, path: str, X_OH: np.ndarray, posture: np.ndarray) -> None:
        """Move the hand drawn under ``path`` (by :meth:`add`) to base pose ``X_OH`` and ``posture``."""
        for body, X_OB in self.body_poses(X_OH, posture).items():
            meshcat.SetTransform(f"{path}/{body}", X_OB)


class ShapeViewer:
    """Meshcat controls and drawing for ``model``'s latent shape space (see the module doc for paths).

    Everything is drawn in the canonical object frame O (= Meshcat's world),
    in metres. The viewer starts on the canonical instance (or the first
    training instance if the canonical one is not among them).

    Args:
        model: a trained :class:`~catgrasp_drake.category_model.CategoryModel`.
        meshcat: the Meshcat to draw into (e.g. from ``start_meshcat()``); the
            viewer adds its sliders to it and owns the ``/view`` subtree.
        show_hand: also draw the hand's geometry at the grasp pose.
        slider_range: the latent sliders span ``[-r, r]`` with r the larger of
            this and the largest training coordinate.
        point_size: Meshcat point size of the clouds (m).
    """

    def __init__(self, model: CategoryModel, meshcat: Meshcat, *, show_hand: bool = True,
                 slider_range: float = 3.0, point_size: float = 0.004):
        if not isinstance(model, CategoryModel):
            raise InputError(f"ShapeViewer: expected a CategoryModel, got {type(model).__name__}")
        self.model = model
        self.meshcat = meshcat
        self.point_size = float(point_size)
        space = model.space
        self._latent_sliders = latent_slider_names(space.q)
        taken = sorted(set(meshcat.GetSliderNames()) & {*self._latent_sliders, INSTANCE_SLIDER})
        if taken:
            raise InputError(f"Meshcat already has sliders {taken}; close() the other viewer first")
        self._hand = _HandDrawer() if show_hand else None

        r = max(float(slider_range), math.ceil(float(np.abs(space.latent_train).max()) * 10) / 10)
        for name in self._latent_sliders:
            meshcat.AddSlider(name, -r, r, SLIDER_STEP, 0.0)
        K = len(model.instances)
        meshcat.AddSlider(INSTANCE_SLIDER, 0, K - 1, 1, 0)

        meshcat.Delete(ROOT)
        draw_cloud(meshcat, f"{ROOT}/canonical", space.canonical, COLORS["canonical"], self.point_size)
        meshcat.SetProperty(f"{ROOT}/canonical", "visible", False)
        if self._hand is not None:
            self._hand.add(meshcat, f"{ROOT}/hand")
        _aim_camera(meshcat, space.canonical)

        self._x = np.zeros(space.q)
        self._points = space.canonical.copy()
        self._motion: GraspMotion | None = None
        self._instance: int | None = None
        self._seen_latent = np.zeros(space.q)
        self._seen_instance = 0
        start = model.instances.index(model.canonical_instance) if model.canonical_instance in model.instances else 0
        self.show_instance(start)

    # ------------------------------------------------------------------ state
    @property
    def x(self) -> np.ndarray:
        """The latent vector (q,) currently drawn (a copy)."""
        return self._x.copy()

    @property
    def points(self) -> np.ndarray:
        """The completed shape (M, 3) currently drawn at ``/view/shape`` (object frame O, m; a copy)."""
        return self._points.copy()

    @property
    def motion(self) -> GraspMotion:
        """The grasp currently drawn: ``model.warped_motion(x)`` (object frame O)."""
        return self._motion

    @property
    def instance(self) -> int | None:
        """Index of the training instance shown, or None once the latent sliders moved away from it."""
        return self._instance

    # ------------------------------------------------------------------ actions
    def set_latent(self, x) -> None:
        """Draw the shape and grasp of latent vector ``x`` (q,) and move the latent sliders to it.

        The sliders show x rounded to their step and clipped to their range;
        the drawing uses x exactly.
        """
        x = self.model.space.check_latent(x)
        if x.shape != (self.model.space.q,):
            raise InputError(f"set_latent: expected one latent vector of shape ({self.model.space.q},), got {x.shape}")
        self._seen_latent = np.array([self.meshcat.SetSliderValue(n, float(v))
                                      for n, v in zip(self._latent_sliders, x)])
        self._instance = None
        self._draw(x)

    def show_instance(self, k) -> None:
        """Show training instance ``k`` (index or name): x = ``latent_train[k]``, sliders moved to it."""
        names = self.model.instances
        if isinstance(k, str):
            if k not in names:
                raise InputError(f"unknown training instance {k!r}; known: {', '.join(names)}")
            k = names.index(k)
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or not (0 <= k < len(names)):
            raise InputError(f"instance index must be an int in [0, {len(names) - 1}], got {k!r}")
        k = int(k)
        self.set_latent(self.model.space.latent_train[k])
        self._seen_instance = int(self.meshcat.SetSliderValue(INSTANCE_SLIDER, k))
        self._instance = k
        self._draw_registered(k)

    def poll(self) -> bool:
        """Read the sliders; redraw if they changed since the last look. Returns whether it redrew.

        A changed ``instance`` slider wins over changed latent sliders.
        """
        k = int(round(self.meshcat.GetSliderValue(INSTANCE_SLIDER)))
        if k != self._seen_instance:
            self.show_instance(k)
            return True
        values = np.array([self.meshcat.GetSliderValue(n) for n in self._latent_sliders])
        if np.array_equal(values, self._seen_latent):
            return False
        self._seen_latent = values
        self._instance = None
        self._draw(values)
        return True

    def export_html(self, path: str | os.PathLike) -> None:
        """Write a self-contained HTML page of all training instances (atomically).

        Built in a separate, temporary localhost Meshcat so that the live
        scene is left as it is. Paths: ``/view/canonical`` (hidden) and, per
        training instance, ``/view/instances/<name>/{shape, pregrasp, grasp,
        hand}``; only the first instance is visible, the reader toggles the
        others in the page's controls.
        """
        model, space = self.model, self.model.space
        out = _quiet_meshcat()
        draw_cloud(out, f"{ROOT}/canonical", space.canonical, COLORS["canonical"], self.point_size)
        out.SetProperty(f"{ROOT}/canonical", "visible", False)
        for k, (name, x) in enumerate(zip(model.instances, space.latent_train)):
            prefix = f"{ROOT}/instances/{name}"
            draw_cloud(out, f"{prefix}/shape", space.deform(x), COLORS["completed"], self.point_size)
            motion = model.warped_motion(x)
            self._draw_grasp(out, prefix, motion)
            if k > 0:
                out.SetProperty(prefix, "visible", False)
        _aim_camera(out, space.canonical)
        save_static_html(out, path)

    def close(self) -> None:
        """Remove this viewer's sliders and its ``/view`` subtree from the Meshcat."""
        for name in [*self._latent_sliders, INSTANCE_SLIDER]:
            self.meshcat.DeleteSlider(name, strict=False)
        self.meshcat.Delete(ROOT)

    # ------------------------------------------------------------------ drawing
    def _draw(self, x: np.ndarray) -> None:
        x = np.array(x, dtype=float)
        points = self.model.space.deform(x)
        motion = self.model.warped_motion(x)
        draw_cloud(self.meshcat, f"{ROOT}/shape", points, COLORS["completed"], self.point_size)
        self._draw_grasp(self.meshcat, ROOT + "/grasp", motion, hand_path=f"{ROOT}/hand")
        self._x, self._points, self._motion = x, points, motion

    def _draw_grasp(self, meshcat: Meshcat, prefix: str, motion: GraspMotion, hand_path: str | None = None) -> None:
        """Triads ``<prefix>/pregrasp`` and ``<prefix>/grasp``; the hand at the grasp pose.

        With ``hand_path`` the hand already drawn there is moved; without it a
        new hand is drawn under ``<prefix>/hand``.
        """
        draw_triad(meshcat, f"{prefix}/pregrasp", motion.pose("pregrasp"), opacity=0.4)
        draw_triad(meshcat, f"{prefix}/grasp", motion.pose("grasp"))
        if self._hand is None:
            return
        if hand_path is None:
            hand_path = f"{prefix}/hand"
            self._hand.add(meshcat, hand_path)
        self._hand.pose(meshcat, hand_path, motion.pose("grasp"), motion.posture(HAND_POSTURE))

    def _draw_registered(self, k: int) -> None:
        space = self.model.space
        registered = space.canonical + space.kernel @ space.W_train[k]
        self.meshcat.Delete(f"{ROOT}/instance")
        path = f"{ROOT}/instance/{self.model.instances[k]}"
        draw_cloud(self.meshcat, path, registered, _REGISTERED_COLOR, self.point_size)
        self.meshcat.SetProperty(path, "visible", False)
