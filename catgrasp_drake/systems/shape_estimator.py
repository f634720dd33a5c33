"""The latent shape estimator: object cloud in the world -> latent shape x and object pose (Alg. 2, line 1).

The maths is :func:`catgrasp_drake.core.inference.infer_latent_pose`; this
module only changes frames (:func:`estimate_on_table`, a pure function) and
moves data between ports and arrays (:class:`LatentShapeEstimator`).

Frames: world W; table top T (z up, the support surface at z = 0), in which
the fit runs so that the core's yaw search turns the model about the
vertical; canonical object frame O (DESIGN.md section 3). The fit gives a
similarity p_T = s R_TO p_O + p_TO; the object pose is its rigid part
``X_WO = X_WT [R_TO, p_TO]`` and ``s`` the scale, so a canonical-frame point
p_O lands at ``X_WO (s p_O)`` in W.

Evaluation model: the estimate is ABSTRACT STATE, written by an
initialization event (the camera sees the object at rest on the table when
the simulation starts); ``estimate_now(context)`` runs the fit on demand
without touching the state (benchmarks, re-perception by a caller, who can
write it with ``set_estimate``). Every output port reads that state only, so
Drake caches the outputs and the fit (30-300 ms) never runs again while the
simulation steps -- unlike an output computed from the cloud, which would
follow the camera's rendering of every step.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.math import RigidTransform
from pydrake.perception import PointCloud
from pydrake.systems.framework import EventStatus, LeafSystem
from scipy.spatial import cKDTree

from catgrasp_drake.core.inference import (
    InferenceResult,
    camera_positions,
    infer_latent_pose,
    model_spacing,
    uncovered_points,
)
from catgrasp_drake.core.shape_space import ShapeSpace
from catgrasp_drake.core.validation import non_negative, real_array, vector3
from catgrasp_drake.errors import CatgraspError, InputError
from catgrasp_drake.perception.object_cloud import cloud_from_points, points_from_cloud, voxel_grid
from catgrasp_drake.prediction import POSTERIOR_TEMPERATURE, hypothesis_weights

#: Fewer observed points than this: no estimate ("no object in view").
MIN_OBSERVED_POINTS = 30
#: ``voxel_size="auto"``: the fit's voxel grid is this many times the model's point spacing
#: (:func:`~catgrasp_drake.core.inference.model_spacing`; 7.1 mm for the drill model -> 9.9 mm, the
#: camera's ~1450 points at 5 mm -> ~440). Unseen-part error on the camera's drills 7.2 -> 6.6 mm
#: (an even density; ``python benchmarks/bench_transfer.py``); 1.0x and 1.2x: 6.9 and 6.7 mm.
AUTO_VOXEL_FACTOR = 1.4


#: When the estimator fits the further views (``view_policy``): "never"; "ambiguous": one more view merged in
#: at a time, while the views so far leave the object's yaw open (:func:`yaw_ambiguous`); "unsure": the same,
#: and also while the grasp's functional part is not in the data (:func:`view_unsure`); "always": every view.
VIEW_POLICIES = ("never", "ambiguous", "unsure", "always")
#: The further views' names, in the order they are taken: their ports are ``<name>_cloud_W``, ``<name>_X_WC``.
EXTRA_VIEWS = ("second", "third")
#: A view is yaw-ambiguous when a shape hypothesis turned at least AMBIGUOUS_YAW_DEG from the MAP fit (about
#: the vertical) keeps a tempered posterior weight above AMBIGUOUS_WEIGHT. Tuned on the COMMITTED mugs (45
#: views, 3 hypotheses; ``python benchmarks/bench_second_view.py``): 19 MAP fits are more than 10 deg off;
#: the rule flags 16 of them and 8 of the 26 right ones (24 second views; 39/45 right after, against 26 with
#: one view and 40 with both views always); weight 0.2: 12 and 6 (35/45). A third view while two still leave
#: it open (session 25, ``benchmarks/results/experiments/s25_views/probe.py``, the same 45 views): 42/45.
AMBIGUOUS_YAW_DEG = 30.0
AMBIGUOUS_WEIGHT = 0.05
#: The functional part of a fit (``functional_part_indices``): its model points within PART_RADIUS_M (m) of the
#: category's functional point (the canonical trigger or handle centre); observed when at least
#: PART_SEEN_FRACTION of them have a data point within PART_NEAR_M (m). Chosen on the COMMITTED instances (session
#: 25, ``benchmarks/results/experiments/s25_views/``): the single-view fits more than 10 deg off (21 mugs, 1 spray
#: bottle) have at most 0.27 of their part observed, the right ones at least 0.65 but for 3 of 24 mugs.
PART_RADIUS_M = 0.02
PART_NEAR_M = 0.01
PART_SEEN_FRACTION = 0.5


def fit_voxel_size(space: ShapeSpace, voxel_size="auto") -> float:
    """The edge (m) of the fit's voxel grid: ``"auto"`` = AUTO_VOXEL_FACTOR x the model's spacing; None/0 = none."""
    if voxel_size is None:
        return 0.0
    if isinstance(voxel_size, str):
        if voxel_size != "auto":
            raise InputError(f"voxel_size: expected 'auto', None or metres, got {voxel_size!r}")
        return AUTO_VOXEL_FACTOR * model_spacing(space)
    v = non_negative(voxel_size, "voxel_size")
    if v > 1.0:
        raise InputError(f"voxel_size: {v:g} m; expected metres (<= 1)")
    return v


@dataclass(frozen=True, eq=False)
class ShapeEstimate:
    """One latent shape + pose estimate, in the world frame.

    ``ok`` False means no estimate could be made (``status`` says why) and
    every other field holds its neutral value (x = 0, identity pose,
    confidence 0). ``X_WO`` 4x4 rigid; ``scale`` dimensionless;
    ``completed_W`` (M, 3) metres; ``result`` the core's result in the
    table frame T; ``timing`` seconds. ``hypotheses``: with the estimator's
    ``hypotheses=k`` > 1, the distinct fits in W, lowest energy first (this
    estimate is the first, with no ``hypotheses`` of its own); else empty.
    ``uncovered``: the observed points (every finite point of the cloud, not
    only those the fit saw) farther than ``core.inference.UNCOVERED_RADIUS_M``
    from every point of ``completed_W`` (-1: no estimate).
    """

    ok: bool
    status: str
    x: np.ndarray
    X_WO: np.ndarray
    scale: float
    completed_W: np.ndarray
    energy: float
    confidence: float
    observed_W: np.ndarray
    result: InferenceResult | None = None
    timing: dict = field(default_factory=dict)
    hypotheses: tuple = ()
    views: int = 1  # camera views fitted: more than 1 when further views were merged in (``view_policy``)
    uncovered: int = -1

    # Contexts deep-copy abstract state; an estimate is never mutated (and holds the shape space).
    def __deepcopy__(self, memo):
        return self

    def __copy__(self):
        return self


def check_table_pose(X_WT) -> np.ndarray:
    """``X_WT`` (RigidTransform or 4x4) as a finite rigid 4x4 matrix within MAX_COORDINATE_M, or InputError."""
    if isinstance(X_WT, RigidTransform):
        X_WT = X_WT.GetAsMatrix4()
    X = real_array(X_WT, "X_WT", "4x4 pose")
    if X.shape != (4, 4) or not np.all(np.isfinite(X)):
        raise InputError(f"X_WT: expected a finite 4x4 pose, got shape {X.shape}")
    R = X[:3, :3]
    if (np.abs(R.T @ R - np.eye(3)).max() > 1e-6 or np.linalg.det(R) < 0
            or np.abs(X[3] - [0, 0, 0, 1]).max() > 1e-9):
        raise InputError("X_WT: not a rigid transform (rotation block not orthonormal or last row not [0, 0, 0, 1])")
    vector3(X[:3, 3], "X_WT translation")
    return X


def failed_estimate(q: int, status: str, observed_W=np.zeros((0, 3))) -> ShapeEstimate:
    return ShapeEstimate(False, status, np.zeros(q), np.eye(4), 1.0, np.zeros((0, 3)), float("inf"), 0.0,
                         np.asarray(observed_W, float).reshape(-1, 3))


def estimate_on_table(space: ShapeSpace, p_W: np.ndarray, X_WT: np.ndarray, *, camera_W=None,
                      yaw_candidates=8, voxel_size="auto", upright: bool = True,
                      **inference_kwargs) -> ShapeEstimate:
    """Fit ``space`` to the object points ``p_W`` (N, 3, world) standing on the table frame ``X_WT`` (4x4).

    ``upright`` (default): the object stands in its canonical stance, so the fitted rotation is a yaw
    about the table normal (``infer_latent_pose(upright=True)``; a free rotation tilted a small real drill
    by 12 deg and its grasp into the table: ``benchmarks/results/experiments/s30_upright``). False: the
    paper's free similarity.

    ``camera_W`` (3,) the camera position in W for the visibility-aware
    E-step (a single view), (K, 3) the cameras of a cloud merged from K views,
    or None (a full cloud). ``yaw_candidates`` as in
    ``infer_latent_pose`` (unknown yaw: 8 starts). ``voxel_size``: the fit
    sees the cloud averaged on a voxel grid of that edge (m; "auto":
    :func:`fit_voxel_size`, matched to the model's spacing; None: the cloud as
    given); the estimate's ``observed_W`` is the cloud as given. Too few points
    give a failed estimate (``ok`` False), never an exception; bad arguments
    raise InputError.
    """
    if not isinstance(space, ShapeSpace):
        raise InputError(f"space: expected a ShapeSpace, got {type(space).__name__}")
    X_WT = check_table_pose(X_WT)
    p_W = real_array(p_W, "p_W", "(N, 3) array")
    if p_W.size == 0:
        p_W = p_W.reshape(0, 3)
    if p_W.ndim != 2 or p_W.shape[1] != 3:
        raise InputError(f"p_W: expected shape (N, 3), got {p_W.shape}")
    p_W = p_W[np.all(np.isfinite(p_W), axis=1)]
    voxel = fit_voxel_size(space, voxel_size)
    if len(p_W) < MIN_OBSERVED_POINTS:
        return failed_estimate(space.q, f"no object in view ({len(p_W)} points < {MIN_OBSERVED_POINTS})", p_W)
    R_WT, p_WT = X_WT[:3, :3], X_WT[:3, 3]
    cam_T = None if camera_W is None else (camera_positions(camera_W) - p_WT) @ R_WT
    p_T = (p_W - p_WT) @ R_WT  # R_TW = R_WT^T
    if voxel > 0.0 and np.all(np.abs(p_T) < voxel * 2.0**40):  # (indices that fit an int64 by far)
        p_vox = voxel_grid(p_T, voxel)  # grid in the table frame: its axes are the fit's
        if len(p_vox) >= MIN_OBSERVED_POINTS:
            p_T = p_vox
    try:
        r = infer_latent_pose(space, p_T, camera_position=cam_T, yaw_candidates=yaw_candidates, upright=upright,
                              **inference_kwargs)
    except CatgraspError as e:
        return failed_estimate(space.q, f"estimate failed: {e}", p_W)

    def in_world(r: InferenceResult) -> ShapeEstimate:
        X_TO = np.eye(4)
        X_TO[:3, :3], X_TO[:3, 3] = r.R, r.t
        completed_W = r.completed @ R_WT.T + p_WT
        return ShapeEstimate(True, "ok", r.x.copy(), X_WT @ X_TO, float(r.s), completed_W, float(r.energy),
                             float(r.confidence), p_W, r, dict(r.timing),
                             uncovered=uncovered_points(completed_W, p_W))

    best = in_world(r)
    if r.hypotheses:
        best = dataclasses.replace(best, hypotheses=(best,) + tuple(in_world(h) for h in r.hypotheses[1:]))
    return best


def functional_yaw(X_WO) -> float:
    """Angle (rad) about the world z of the object's functional direction (+y of O projected on the xy plane)."""
    X = np.asarray(X_WO, float)
    return float(np.arctan2(X[1, 1], X[0, 1]))


def yaw_ambiguous(estimate: ShapeEstimate, *, min_weight: float = AMBIGUOUS_WEIGHT,
                  min_yaw_deg: float = AMBIGUOUS_YAW_DEG, temperature: float = POSTERIOR_TEMPERATURE) -> bool:
    """Whether ``estimate``'s shape posterior leaves the object's yaw open: a hypothesis (finite energy) turned at
    least ``min_yaw_deg`` from the MAP fit holds a tempered weight (``prediction.hypothesis_weights``) above
    ``min_weight``. An estimate without hypotheses (a single fit) is never ambiguous."""
    fits = [h for h in estimate.hypotheses if np.isfinite(h.energy)] if estimate.ok else []
    if len(fits) < 2:
        return False
    w = hypothesis_weights([h.energy for h in fits], temperature)
    yaw0 = functional_yaw(fits[0].X_WO)
    for h, wi in zip(fits[1:], w[1:]):
        turn = abs((functional_yaw(h.X_WO) - yaw0 + np.pi) % (2.0 * np.pi) - np.pi)
        if wi > min_weight and np.degrees(turn) >= min_yaw_deg:
            return True
    return False


def functional_part_indices(space: ShapeSpace, point_O, radius: float = PART_RADIUS_M) -> np.ndarray:
    """Indices of the model points of ``space`` within ``radius`` (m) of ``point_O`` (3,), the category's functional
    point in the canonical frame (e.g. ``grasping.descriptor.motion_functional_point`` of the canonical motion)."""
    if not isinstance(space, ShapeSpace):
        raise InputError(f"space: expected a ShapeSpace, got {type(space).__name__}")
    point_O = vector3(point_O, "functional point")
    radius = non_negative(radius, "radius")
    return np.flatnonzero(np.linalg.norm(space.canonical - point_O, axis=1) <= radius)


def part_seen_fraction(estimate: ShapeEstimate, part, near: float = PART_NEAR_M) -> float:
    """The fraction of the fitted shape's points ``part`` (indices into its model points) with an observed point
    within ``near`` (m): how much of that part is in the data rather than completed by the fit. 1.0 when
    ``part`` is empty; 0.0 for a failed estimate."""
    part = np.asarray(part, dtype=int).reshape(-1)
    if not estimate.ok or len(estimate.observed_W) == 0:
        return 0.0
    if len(part) == 0:
        return 1.0
    d, _ = cKDTree(estimate.observed_W).query(estimate.completed_W[part])
    return float((d <= near).mean())


def view_unsure(estimate: ShapeEstimate, part=None, *, min_seen: float = PART_SEEN_FRACTION) -> bool:
    """Whether another view should be taken: the fit's yaw is ambiguous (:func:`yaw_ambiguous`), or less than
    ``min_seen`` of its functional part ``part`` (model-point indices, :func:`functional_part_indices`; None:
    not checked) is observed (:func:`part_seen_fraction`) -- where the grasp goes was completed, not seen."""
    if yaw_ambiguous(estimate):
        return True
    return part is not None and estimate.ok and part_seen_fraction(estimate, part) < min_seen


def estimate_with_views(space: ShapeSpace, p_W: np.ndarray, X_WT: np.ndarray, *, camera_W=None, extra_views=(),
                        policy: str = "ambiguous", part=None, **kwargs) -> ShapeEstimate:
    """:func:`estimate_on_table` of the first view (``p_W``, seen from ``camera_W``), then -- by ``policy``
    (:data:`VIEW_POLICIES`) -- of the views merged with the further ``extra_views``, in the order they are
    taken: "ambiguous" merges one more at a time while the fit so far leaves the yaw open; "unsure" also while
    less than half the functional part ``part`` (model-point indices, :func:`functional_part_indices`) is
    observed (:func:`view_unsure`); "always" merges every view at once. Each further view is a pair
    ``(points_W (M, 3), camera position (3,) or None)``, or a callable returning one, called only when the view
    is taken (a camera rendered only when needed). With every merged view's camera position the merged fit is
    visibility-aware (a model point is a mixture centre when any of those cameras sees it); without them, it
    is fitted like a full cloud. Views without points are skipped. The result's ``views`` counts the views
    fitted; ``timing["earlier_views"]`` holds the time of the fits before the last (s)."""
    if policy not in VIEW_POLICIES:
        raise InputError(f"view policy: expected one of {VIEW_POLICIES}, got {policy!r}")
    further = list(extra_views)
    for k, view in enumerate(further):
        if not callable(view):
            further[k] = _view_pair(view, k)  # (checked now; a callable's view when it is taken)
    views = [(np.asarray(p_W, float).reshape(-1, 3), camera_W)]
    fit = estimate_on_table(space, views[0][0], X_WT, camera_W=camera_W, **kwargs)
    if policy == "never":
        return fit

    def taken(k: int):  # the k-th further view, or None when it has no points
        view = _view_pair(further[k](), k) if callable(further[k]) else further[k]
        return view if view[0].size else None

    earlier, k = 0.0, 0
    while k < len(further):
        if policy == "always":
            new = [v for v in (taken(j) for j in range(k, len(further))) if v is not None]
            k = len(further)
        elif (view_unsure(fit, part) if policy == "unsure" else yaw_ambiguous(fit)):
            new = [v for v in (taken(k),) if v is not None]
            k += 1
        else:
            break
        if not new:
            continue
        earlier += float(sum(v for v in fit.timing.values() if isinstance(v, (int, float))))
        views += new
        cameras = None
        if all(c is not None for _, c in views):
            cameras = np.vstack([camera_positions(c) for _, c in views])
        fit = estimate_on_table(space, np.vstack([p for p, _ in views]), X_WT, camera_W=cameras, **kwargs)
        n = len(views)
        fit = dataclasses.replace(fit, views=n, timing=dict(fit.timing) | {"earlier_views": earlier},
                                  hypotheses=tuple(dataclasses.replace(h, views=n) for h in fit.hypotheses))
    return fit


def _view_pair(view, k: int) -> tuple:
    """Further view ``k`` as ``(points (M, 3) float, camera position or None)``, or InputError."""
    try:
        points, camera = view
    except (TypeError, ValueError):
        raise InputError(f"extra_views[{k}]: expected a pair (points_W, camera position or None)") from None
    points = np.zeros((0, 3)) if points is None else real_array(points, f"extra_views[{k}] points", "(M, 3)")
    return points.reshape(-1, 3), camera


class LatentShapeEstimator(LeafSystem):
    """Latent shape x and object pose from the object's point cloud (module docstring: frames, events).

    .. pydrake_system::

        name: LatentShapeEstimator
        input_ports:
        - object_cloud_W
        - X_WC (optional)
        - second_cloud_W (optional)
        - second_X_WC (optional)
        - third_cloud_W (optional)
        - third_X_WC (optional)
        output_ports:
        - x
        - X_WO
        - scale
        - completed_cloud_W
        - observed_cloud_W
        - energy
        - confidence
        - estimate

    Input ports:
        object_cloud_W: ``PointCloud`` (xyz, metres, world frame W), the segmented object.
        X_WC: ``RigidTransform``, pose of the camera C in W (single view: its
            position turns on the visibility-aware fit); leave it
            unconnected for a full (multi-view) cloud.
        second_cloud_W, third_cloud_W: ``PointCloud`` (W, metres) of the object
            seen by further cameras (:data:`EXTRA_VIEWS`, in that order),
            merged in by the ``view_policy`` (:func:`estimate_with_views`);
            unconnected: not taken.
        second_X_WC, third_X_WC: ``RigidTransform``, pose of that camera in W
            (with ``X_WC``: the merged fit is visibility-aware for every camera).
    Output ports:
        x: latent vector (q,), whitened (N(0, I) over the category).
        X_WO: ``RigidTransform``, rigid part of the fitted pose of the canonical frame O in W.
        scale: (1,) uniform scale s of the canonical shape.
        completed_cloud_W: ``PointCloud``, the completed shape in W (metres).
        observed_cloud_W: ``PointCloud``, the cloud given to the fit (W, metres; before
            the fit's voxel grid): unlike the camera's port it does not change while
            the simulation steps.
        energy: (1,) final fit energy (negative log-likelihood + prior).
        confidence: (1,) in [0, 1]; 0 when there is no estimate.
        estimate: ``ShapeEstimate`` (everything above plus status and timings).
    Parameters (constructor): the category's ``ShapeSpace``, the table pose
    ``X_WT`` (4x4), ``yaw_candidates`` (8: unknown yaw), ``voxel_size`` (the
    fit's voxel grid, as in :func:`estimate_on_table`; resolved once here) and
    extra keyword arguments for ``infer_latent_pose`` (e.g.
    ``**core.inference.LEGACY_SEARCH`` with ``voxel_size=None``: the settings
    before issue 17); ``view_policy`` (:data:`VIEW_POLICIES`, "never" by
    default): when the further cameras' clouds are merged in;
    ``functional_point_O`` (3,) m, canonical frame: the category's functional
    point, whose part of the fit the "unsure" policy wants observed (None:
    the yaw's ambiguity alone decides).
    """

    def __init__(self, space: ShapeSpace, X_WT, *, yaw_candidates=8, voxel_size="auto", view_policy: str = "never",
                 functional_point_O=None, **inference_kwargs):
        super().__init__()
        if not isinstance(space, ShapeSpace):
            raise InputError(f"space: expected a ShapeSpace, got {type(space).__name__}")
        self._space = space
        self._X_WT = check_table_pose(X_WT)
        self._yaws = yaw_candidates
        self._voxel = fit_voxel_size(space, voxel_size)
        self._kwargs = dict(inference_kwargs)
        if view_policy not in VIEW_POLICIES:
            raise InputError(f"view_policy: expected one of {VIEW_POLICIES}, got {view_policy!r}")
        self._view_policy = view_policy
        self._part = None if functional_point_O is None else functional_part_indices(space, functional_point_O)
        self._cloud_in = self.DeclareAbstractInputPort("object_cloud_W", AbstractValue.Make(PointCloud()))
        self._camera_in = self.DeclareAbstractInputPort("X_WC", AbstractValue.Make(RigidTransform()))
        self._extra_in = [(self.DeclareAbstractInputPort(f"{name}_cloud_W", AbstractValue.Make(PointCloud())),
                           self.DeclareAbstractInputPort(f"{name}_X_WC", AbstractValue.Make(RigidTransform())))
                          for name in EXTRA_VIEWS]
        self._state = self.DeclareAbstractState(AbstractValue.Make(failed_estimate(space.q, "not yet estimated")))
        self.DeclareInitializationUnrestrictedUpdateEvent(self._update)
        state_only = {self.abstract_state_ticket(self._state)}
        q = space.q
        self.DeclareVectorOutputPort("x", q, lambda c, o: o.SetFromVector(self._get(c).x),
                                     prerequisites_of_calc=state_only)
        self.DeclareAbstractOutputPort("X_WO", lambda: AbstractValue.Make(RigidTransform()),
                                       lambda c, o: o.set_value(RigidTransform(self._get(c).X_WO)),
                                       prerequisites_of_calc=state_only)
        self.DeclareVectorOutputPort("scale", 1, lambda c, o: o.SetFromVector([self._get(c).scale]),
                                     prerequisites_of_calc=state_only)
        self.DeclareAbstractOutputPort("completed_cloud_W", lambda: AbstractValue.Make(PointCloud()),
                                       lambda c, o: o.set_value(cloud_from_points(self._get(c).completed_W)),
                                       prerequisites_of_calc=state_only)
        self.DeclareAbstractOutputPort("observed_cloud_W", lambda: AbstractValue.Make(PointCloud()),
                                       lambda c, o: o.set_value(cloud_from_points(self._get(c).observed_W)),
                                       prerequisites_of_calc=state_only)
        self.DeclareVectorOutputPort("energy", 1, lambda c, o: o.SetFromVector([self._get(c).energy]),
                                     prerequisites_of_calc=state_only)
        self.DeclareVectorOutputPort("confidence", 1, lambda c, o: o.SetFromVector([self._get(c).confidence]),
                                     prerequisites_of_calc=state_only)
        self.DeclareAbstractOutputPort("estimate", lambda: AbstractValue.Make(failed_estimate(q, "")),
                                       lambda c, o: o.set_value(self._get(c)), prerequisites_of_calc=state_only)

    @property
    def space(self) -> ShapeSpace:
        return self._space

    @property
    def inference_kwargs(self) -> dict:
        """The ``infer_latent_pose`` options every fit of this estimator uses (a copy)."""
        return dict(self._kwargs)

    def _get(self, context) -> ShapeEstimate:
        return context.get_abstract_state(int(self._state)).get_value()

    def estimate_now(self, context) -> ShapeEstimate:
        """Run the fit on the current input cloud (does not change the state)."""
        p_W = points_from_cloud(self._cloud_in.Eval(context))
        camera_W = None
        if self._camera_in.HasValue(context):
            camera_W = self._camera_in.Eval(context).translation()
        def view(cloud_in, camera_in):  # rendered only if the policy takes it
            return lambda: (points_from_cloud(cloud_in.Eval(context)),
                            camera_in.Eval(context).translation() if camera_in.HasValue(context) else None)

        extra = []
        for cloud_in, camera_in in self._extra_in:
            if not cloud_in.HasValue(context):
                break  # the views are taken in order
            extra.append(view(cloud_in, camera_in))
        return estimate_with_views(self._space, p_W, self._X_WT, camera_W=camera_W, extra_views=extra,
                                   policy=self._view_policy, part=self._part, yaw_candidates=self._yaws,
                                   voxel_size=self._voxel, **self._kwargs)

    def set_estimate(self, context, estimate: ShapeEstimate) -> None:
        """Write ``estimate`` into this system's state in ``context``."""
        if not isinstance(estimate, ShapeEstimate):
            raise InputError(f"estimate: expected a ShapeEstimate, got {type(estimate).__name__}")
        context.get_mutable_abstract_state(int(self._state)).set_value(estimate)

    def _update(self, context, state):
        state.get_mutable_abstract_state(int(self._state)).set_value(self.estimate_now(context))
        return EventStatus.Succeeded()
