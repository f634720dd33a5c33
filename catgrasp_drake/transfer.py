"""The grasp transfer diagram (paper, Algorithm 2) and one-call execution of it.

``make_transfer_diagram(scenario, model, meshcat=None, view="single")``
adds to the station's ``DiagramBuilder``::

    camera (RgbdSensor) -> <camera>_object_cloud (ObjectCloudSystem: label mask,
        DepthImageToPointCloud, crop, voxel grid)   [view="full": 4 cameras, merged]
      -> shape_estimator (LatentShapeEstimator: x, X_WO, scale, completed cloud, confidence)
      -> grasp_regressor (GraspRegressor: grasp motion in W)
      -> grasp_trajectory (MotionPlanner: IK plan, arm/hand desired states)
      -> plant (PD-gained actuators of the UR10 and the SVH hand)

and, with Meshcat, ``transfer_visualizer`` (observed cloud, completed shape,
control-pose triads, the hand's planned path; each a toggleable path under
``/transfer``). Running the diagram's simulator is all a user needs: the
estimate is made by an initialization event, the rest follows through
Drake's caches. :func:`run_transfer` does the same stage by stage, to time
each stage, and judges the outcome with the station's judge.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import asdict, dataclass, field

import numpy as np
import trimesh
from pydrake.common.value import AbstractValue
from pydrake.geometry import Meshcat, Rgba
from pydrake.perception import Concatenate, PointCloud
from pydrake.systems.analysis import InitializeParams
from pydrake.systems.framework import DiagramBuilder, EventStatus, LeafSystem

from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.core.visibility import camera_on_sphere_position
from catgrasp_drake.errors import InputError
from catgrasp_drake.grasping.descriptor import motion_functional_point
from catgrasp_drake.perception.object_cloud import points_from_cloud
from catgrasp_drake.planning.model import make_planning_model, object_mesh_path
from catgrasp_drake.planning.records import PlanParams, hold_plan
from catgrasp_drake.prediction import ESTIMATORS, check_method, estimator_kwargs, rigid_space
from catgrasp_drake.robot.models import ARM_JOINTS, HAND_BASE_LINK
from catgrasp_drake.station.builder import StationHandles, add_station, make_station
from catgrasp_drake.station.scenario import CameraSpec, Scenario
from catgrasp_drake.systems.grasp_execution import MotionPlanner, placeholder_motion_W
from catgrasp_drake.systems.predictors import GraspPredictor
from catgrasp_drake.systems.shape_estimator import EXTRA_VIEWS, LatentShapeEstimator, ShapeEstimate
from catgrasp_drake.trial import judge_spec, pose_tuple, simulate_and_judge
from catgrasp_drake.viz.meshcat_tools import COLORS, draw_cloud, draw_triad

#: "single": one camera, the visibility-aware fit (the benchmark's measure); "active": the same, and further
#: cameras' views (:data:`EXTRA_VIEW_AZIMUTHS_DEG`) merged in one at a time while the views so far leave the
#: object's yaw open or the grasp's functional part unobserved (``systems.shape_estimator.view_unsure``; at
#: most three views); "two" / "three": the first two / three views always; "full": FULL_VIEW_CAMERAS cameras
#: on a ring, merged.
VIEWS = ("single", "active", "two", "three", "full")
#: The views with further cameras: the estimator's policy for them, and how many further cameras.
EXTRA_VIEW_POLICY = {"active": ("unsure", 2), "two": ("always", 1), "three": ("always", 2)}
#: The further cameras: the first turned this far (deg, counter-clockwise seen from above) about the vertical
#: through the point it looks at -- same distance, same height -- in the order they are taken. +90 and -90
#: were compared for the second on the committed mugs with the first, visibility-free merged fit (``python
#: benchmarks/bench_second_view.py --azimuths 90 -90 --no-visibility``: yaw within 10 deg on 42/45 and 31/45
#: views with both views always); the third looks from the other side (session 25: with all three views
#: always, 45/45; ``benchmarks/results/experiments/s25_views/probe.py``).
EXTRA_VIEW_AZIMUTHS_DEG = (90.0, -90.0)
#: Cameras of the "full" view: on a ring around the object, this far (m) and this high (deg).
FULL_VIEW_CAMERAS = 4
FULL_VIEW_DISTANCE = 0.75
FULL_VIEW_ELEVATION_DEG = 40.0


def ring_cameras(scenario: Scenario, n: int = FULL_VIEW_CAMERAS, distance: float = FULL_VIEW_DISTANCE,
                 elevation_deg: float = FULL_VIEW_ELEVATION_DEG) -> tuple[CameraSpec, ...]:
    """``n`` cameras evenly spaced on a ring around the object's initial position, looking at it."""
    base = scenario.cameras[0] if scenario.cameras else CameraSpec()
    target = scenario.X_WO()[:3, 3] + np.array([0.0, 0.0, 0.08])
    el = np.radians(elevation_deg)
    cams = []
    for k in range(n):
        az = 2 * np.pi * k / n + np.pi / 4
        eye = camera_on_sphere_position(target, distance, az, el)
        cams.append(CameraSpec(name=f"ring{k}", look_at_eye=tuple(eye), look_at_target=tuple(target), width=base.width,
                               height=base.height, fov_y_deg=base.fov_y_deg, depth_range=base.depth_range))
    return tuple(cams)


def turned_camera(first: CameraSpec, azimuth_deg: float = EXTRA_VIEW_AZIMUTHS_DEG[0],
                  name: str = "second_view") -> CameraSpec:
    """The camera ``first`` turned ``azimuth_deg`` about the vertical through its target (same distance, height,
    intrinsics), named ``name``."""
    X_WC = first.X_WC_matrix()
    eye = X_WC[:3, 3]
    target = np.asarray(first.look_at_target if first.look_at_target is not None else eye + 0.8 * X_WC[:3, 2], float)
    a = np.radians(azimuth_deg)
    R = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
    eye2 = target + R @ (eye - target)
    return dataclasses.replace(first, name=name, X_WC=None, look_at_eye=tuple(float(v) for v in eye2),
                               look_at_target=tuple(float(v) for v in target))


class CloudMerger(LeafSystem):
    """Concatenates point clouds (Drake's ``Concatenate``).

    .. pydrake_system::

        name: CloudMerger
        input_ports:
        - cloud_0
        - ...
        - cloud_{n-1}
        output_ports:
        - point_cloud_W

    Input ports:
        cloud_0 ... cloud_{n-1}: ``PointCloud`` (xyz, metres, world frame W).
    Output ports:
        point_cloud_W: ``PointCloud``, all points, in W.
    """

    def __init__(self, n: int):
        super().__init__()
        self._ins = [self.DeclareAbstractInputPort(f"cloud_{i}", AbstractValue.Make(PointCloud())) for i in range(n)]
        self.DeclareAbstractOutputPort("point_cloud_W", lambda: AbstractValue.Make(PointCloud()),
                                       lambda c, o: o.set_value(Concatenate([p.Eval(c) for p in self._ins])))


class TransferVisualizer(LeafSystem):
    """Draws the transfer's intermediate results on Meshcat once, when the simulation starts.

    .. pydrake_system::

        name: TransferVisualizer
        input_ports:
        - object_cloud_W
        - estimate
        - grasp_motion_W
        - plan

    Input ports:
        object_cloud_W: ``PointCloud`` the camera's object cloud (W).
        estimate: ``ShapeEstimate`` (completed shape in W).
        grasp_motion_W: ``GraspMotion`` (control poses in W).
        plan: ``GraspPlan`` (joint knots; the hand's path is computed with the planning model).
    Meshcat paths (each toggleable in the Meshcat controls):
        /transfer/observed (blue), /transfer/completed (green),
        /transfer/control_poses/<name> (triads), /transfer/planned_path (orange line).
    """

    def __init__(self, meshcat: Meshcat, planning_model):
        super().__init__()
        self._meshcat = meshcat
        self._planning = planning_model
        self._cloud = self.DeclareAbstractInputPort("object_cloud_W", AbstractValue.Make(PointCloud()))
        self._estimate = self.DeclareAbstractInputPort("estimate", AbstractValue.Make(object()))
        self._motion = self.DeclareAbstractInputPort("grasp_motion_W", AbstractValue.Make(
            placeholder_motion_W()))
        self._plan = self.DeclareAbstractInputPort("plan", AbstractValue.Make(
            hold_plan(np.zeros(6), np.zeros(9), "")))
        self.DeclareInitializationPublishEvent(self._draw)

    def _draw(self, context):
        draw_transfer(self._meshcat, points_from_cloud(self._cloud.Eval(context)), self._estimate.Eval(context),
                      self._motion.Eval(context), self._plan.Eval(context), self._planning)
        return EventStatus.Succeeded()


def hand_path_W(planning_model, plan) -> np.ndarray:
    """Positions (K, 3) of the hand base in W at the plan's arm knots (forward kinematics, planning model)."""
    plant = planning_model.plant
    ctx = plant.CreateDefaultContext()
    frame = plant.GetFrameByName(HAND_BASE_LINK, planning_model.hand)
    joints = [plant.GetJointByName(n, planning_model.arm) for n in ARM_JOINTS]
    out = []
    for q in plan.q_arm:
        for j, v in zip(joints, q):
            j.set_angle(ctx, float(v))
        out.append(frame.CalcPoseInWorld(ctx).translation())
    return np.array(out)


def draw_transfer(meshcat: Meshcat, observed_W, estimate: ShapeEstimate, motion_W, plan, planning_model) -> None:
    """Observed cloud, completed shape, control-pose triads and planned hand path under ``/transfer``."""
    meshcat.Delete("/transfer")
    if len(observed_W):
        draw_cloud(meshcat, "/transfer/observed", observed_W, COLORS["observed"])
    if estimate.ok:
        draw_cloud(meshcat, "/transfer/completed", estimate.completed_W, COLORS["completed"])
        for name, X in zip(motion_W.pose_names, motion_W.poses):
            draw_triad(meshcat, f"/transfer/control_poses/{name}", X, length=0.06)
    if plan.ok:
        path = hand_path_W(planning_model, plan)
        meshcat.SetLine("/transfer/planned_path", path.T, 3.0, Rgba(1.0, 0.55, 0.0, 1.0))


@dataclass
class TransferDiagram:
    """A built transfer diagram and handles to its systems."""

    diagram: object
    station: StationHandles
    estimator: LatentShapeEstimator
    regressor: GraspPredictor
    generator: MotionPlanner
    cloud_port: object  # the output port feeding the estimator
    view: str
    model: CategoryModel
    meshcat: Meshcat | None = None
    method: str = "latent"


def true_object_points_W(scenario: Scenario) -> np.ndarray:
    """Vertices (N, 3) of the scenario's true object mesh at its initial pose, in W (the ablation's obstacle)."""
    path = object_mesh_path(scenario.object)
    if path is None:
        raise InputError("the true-object planner needs a data-set or imported object with its mesh, not a primitive")
    mesh = trimesh.load(path, force="mesh", process=False)
    X = scenario.X_WO()
    return np.asarray(mesh.vertices, float) @ X[:3, :3].T + X[:3, 3]


def make_transfer_diagram(scenario: Scenario, model: CategoryModel, meshcat: Meshcat | None = None, *,
                          view: str = "single", camera: str | None = None, min_confidence: float = 0.0,
                          params: PlanParams = PlanParams(), yaw_candidates=8, method: str = "latent",
                          **inference_kwargs) -> TransferDiagram:
    """The station with the transfer systems wired in (module docstring); see :class:`TransferDiagram`.

    ``view`` "single": the scenario's camera ``camera`` (default its first)
    with the visibility-aware fit; "active" / "two" / "three": the same, and
    further cameras (:func:`turned_camera`, :data:`EXTRA_VIEW_AZIMUTHS_DEG`)
    whose views the estimator merges in while the yaw is open / always;
    "full": ``FULL_VIEW_CAMERAS`` cameras on a ring around the object,
    clouds merged, no visibility model.
    ``min_confidence``: below it the motion is refused (status "refused: ...").
    ``method`` (:mod:`catgrasp_drake.prediction`): "latent" (this project),
    or a baseline -- "paper" (no visibility model), "rigid", "cpd", "nearest"
    -- each with its own estimator set-up and a :class:`GraspPredictor`; or
    the ablation "true_object" (latent, planned around the true object).
    """
    if not isinstance(model, CategoryModel):
        raise InputError(f"model: expected a CategoryModel, got {type(model).__name__}")
    if view not in VIEWS:
        raise InputError(f"view: expected one of {VIEWS}, got {view!r}")
    setup = ESTIMATORS[check_method(method)]
    if scenario.object.category is not None and scenario.object.category != model.category:
        raise InputError(f"the scenario's object is a {scenario.object.category!r}, the model is for "
                         f"{model.category!r}")
    if view == "full":
        scenario = scenario.replace(cameras=ring_cameras(scenario))
    elif not scenario.cameras:
        raise InputError(f"scenario {scenario.name!r} has no camera; a single view needs one")
    elif view in EXTRA_VIEW_POLICY:
        first = [c for c in scenario.cameras if c.name == (camera or scenario.cameras[0].name)]
        if not first:
            raise InputError(f"camera {camera!r} not in scenario {scenario.name!r}; "
                             f"cameras: {sorted(c.name for c in scenario.cameras)}")
        extra = EXTRA_VIEW_POLICY[view][1]
        scenario = scenario.replace(cameras=(first[0],) + tuple(
            turned_camera(first[0], az, f"{name}_view")
            for name, az in zip(EXTRA_VIEWS[:extra], EXTRA_VIEW_AZIMUTHS_DEG)))
    builder = DiagramBuilder()
    h = add_station(builder, scenario, meshcat)
    space = rigid_space(model.space) if setup.rigid else model.space
    inference_kwargs = estimator_kwargs(method, model.category) | inference_kwargs  # (the caller's options win)
    estimator = builder.AddNamedSystem("shape_estimator", LatentShapeEstimator(
        space, scenario.table.pose.matrix(), yaw_candidates=yaw_candidates,
        view_policy=EXTRA_VIEW_POLICY.get(view, ("never", 0))[0],
        functional_point_O=motion_functional_point(model.template, model.grasp_anchor_H), **inference_kwargs))
    extra_views = EXTRA_VIEWS[:EXTRA_VIEW_POLICY.get(view, ("never", 0))[1]]
    for name in extra_views:
        builder.Connect(h.object_clouds[f"{name}_view"].GetOutputPort("object_cloud_W"),
                        estimator.GetInputPort(f"{name}_cloud_W"))
    if view != "full":
        name = camera or scenario.cameras[0].name
        if name not in h.cameras:
            raise InputError(f"camera {name!r} not in scenario {scenario.name!r}; cameras: {sorted(h.cameras)}")
        cloud_port = h.object_clouds[name].GetOutputPort("object_cloud_W")
        if setup.visibility:
            builder.Connect(h.cameras[name].body_pose_in_world_output_port(), estimator.GetInputPort("X_WC"))
            for name in extra_views:
                builder.Connect(h.cameras[f"{name}_view"].body_pose_in_world_output_port(),
                                estimator.GetInputPort(f"{name}_X_WC"))
    else:
        merger = builder.AddNamedSystem("cloud_merger", CloudMerger(len(h.cameras)))
        for i, name in enumerate(h.cameras):
            builder.Connect(h.object_clouds[name].GetOutputPort("object_cloud_W"), merger.get_input_port(i))
        cloud_port = merger.get_output_port()
    builder.Connect(cloud_port, estimator.GetInputPort("object_cloud_W"))
    regressor = builder.AddNamedSystem("grasp_regressor", GraspPredictor(model, method))
    for port in ("x", "X_WO", "scale"):
        builder.Connect(estimator.GetOutputPort(port), regressor.GetInputPort(port))
    if method == "cpd":
        # the estimate's copy of the cloud (state), not the camera's port: the camera renders every step,
        # which would re-run CPD and the planner at every step
        builder.Connect(estimator.GetOutputPort("observed_cloud_W"), regressor.GetInputPort("observed_cloud_W"))
        builder.Connect(estimator.GetOutputPort("completed_cloud_W"), regressor.GetInputPort("completed_cloud_W"))
    if method == "true_object":
        # the true object is known before the simulation starts: it is part of the planning model, not an
        # input port (a constant source's port would be re-evaluated, and the plan re-made, at every step)
        planning = make_planning_model(scenario, true_object_points_W(scenario))
        generator = builder.AddNamedSystem("grasp_trajectory", MotionPlanner(
            h.plant, h.arm, h.hand, planning, params=params, min_confidence=min_confidence))
    else:
        planning = make_planning_model(scenario)
        generator = builder.AddNamedSystem("grasp_trajectory", MotionPlanner(
            h.plant, h.arm, h.hand, planning, obstacle_model=planning.with_obstacle,
            params=params, min_confidence=min_confidence))
        builder.Connect(estimator.GetOutputPort("completed_cloud_W"), generator.GetInputPort("object_cloud_W"))
    builder.Connect(regressor.GetOutputPort("grasp_motion_W"), generator.GetInputPort("grasp_motion_W"))
    if setup.hypotheses > 1:  # a grasp per shape hypothesis, ranked; the planner executes the first feasible
        builder.Connect(estimator.GetOutputPort("estimate"), regressor.GetInputPort("estimate"))
        builder.Connect(regressor.GetOutputPort("grasp_candidates_W"), generator.GetInputPort("grasp_candidates_W"))
    builder.Connect(estimator.GetOutputPort("confidence"), generator.GetInputPort("confidence"))
    builder.Connect(generator.GetOutputPort("arm_desired_state"), h.plant.get_desired_state_input_port(h.arm))
    builder.Connect(generator.GetOutputPort("hand_desired_state"), h.plant.get_desired_state_input_port(h.hand))
    if meshcat is not None:
        viz = builder.AddNamedSystem("transfer_visualizer", TransferVisualizer(meshcat, planning))
        builder.Connect(cloud_port, viz.GetInputPort("object_cloud_W"))
        builder.Connect(estimator.GetOutputPort("estimate"), viz.GetInputPort("estimate"))
        builder.Connect(regressor.GetOutputPort("grasp_motion_W"), viz.GetInputPort("grasp_motion_W"))
        builder.Connect(generator.GetOutputPort("plan"), viz.GetInputPort("plan"))
    diagram = builder.Build()
    diagram.set_name("grasp_transfer")
    return TransferDiagram(diagram, h, estimator, regressor, generator, cloud_port, view, model, meshcat, method)


@dataclass(frozen=True)
class TransferResult:
    """Outcome of one transfer: the estimate, the predicted motion, the plan and the judged execution."""

    category: str
    instance: str | None
    view: str
    grasp_success: bool
    functional_success: bool
    failure_reason: str | None
    detail: str
    plan_status: str
    confidence: float
    scale: float
    X_WO_estimated: tuple
    X_WO_true: tuple
    object_rise_m: float
    object_tilt_deg: float
    num_observed_points: int
    timings: dict = field(default_factory=dict)  # seconds per stage
    #: What the judge measured (NaN where not measured): the force along the trigger's travel (N),
    #: the object's largest shift (m) and turn (deg) in the hand after the start of the hold.
    judge: dict = field(default_factory=dict)
    #: The shape posterior's part: ``hypotheses`` (distinct fits; 1 without a posterior), ``search_rank``
    #: (the MAP fit's start in the yaw search's energy order; 0 = the search's best, as without one), ``candidate``
    #: (rank of the executed grasp among the candidates; 0 = the first choice), ``tried`` (candidates
    #: planned), ``hypothesis`` (the executed grasp's fit in energy order; 0 = the MAP fit), ``support``.
    posterior: dict = field(default_factory=dict)
    #: Camera views the estimate fitted: 1, or more when the "active"/"two"/"three" view merged further ones in.
    views_used: int = 1

    def to_dict(self) -> dict:
        return asdict(self)


def run_transfer(td: TransferDiagram, *, record_html=None, return_context: bool = False, on_phase=None):
    """Perceive, estimate, regress, plan, execute and judge once (stage timings in ``timings``).

    Equivalent to simulating ``td.diagram`` from its default context (the
    initialization event would make the same estimate); here each stage is
    run explicitly first so that its time can be measured, then the
    simulation starts with initialization events suppressed. Returns the
    :class:`TransferResult` (and the final root context with ``return_context``).
    ``on_phase(label, root_context)`` is called at the phases of the motion
    (``catgrasp_drake.trial.simulate_and_judge``), e.g. to film it.
    """
    h = td.station
    timings = {}
    t_all = time.perf_counter()
    context = td.diagram.CreateDefaultContext()
    t0 = time.perf_counter()
    observed = points_from_cloud(td.cloud_port.Eval(td.cloud_port.get_system().GetMyContextFromRoot(context)))
    timings["perceive"] = time.perf_counter() - t0  # render depth + label, back-project, crop, voxel grid
    est_ctx = td.estimator.GetMyMutableContextFromRoot(context)
    t0 = time.perf_counter()
    estimate = td.estimator.estimate_now(est_ctx)
    timings["estimate"] = time.perf_counter() - t0
    td.estimator.set_estimate(est_ctx, estimate)
    t0 = time.perf_counter()
    motion = td.regressor.GetOutputPort("grasp_motion_W").Eval(td.regressor.GetMyContextFromRoot(context))
    timings["regress"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    plan = td.generator.GetOutputPort("plan").Eval(td.generator.GetMyContextFromRoot(context))
    timings["plan"] = time.perf_counter() - t0
    candidates = td.regressor.GetOutputPort("grasp_candidates_W").Eval(td.regressor.GetMyContextFromRoot(context))
    chosen = candidates[plan.candidate]  # the executed grasp (the only candidate without a posterior)
    motion = chosen.motion
    search_rank = estimate.result.diagnostics.get("search_rank", 0) if estimate.result is not None else 0
    posterior = {"hypotheses": max(1, len(estimate.hypotheses)), "search_rank": int(search_rank),
                 "candidate": int(plan.candidate),
                 "tried": int(plan.tried), "hypothesis": int(chosen.hypothesis), "support": float(chosen.support)}
    if td.meshcat is not None:
        draw_transfer(td.meshcat, observed, estimate, motion, plan, td.generator.planning_model)
    spec = judge_spec(h, motion.lift_height)
    X_true = h.scenario.X_WO()
    base = dict(category=td.model.category, instance=h.scenario.object.instance, view=td.view,
                plan_status=plan.status, confidence=float(estimate.confidence), scale=float(estimate.scale),
                X_WO_estimated=pose_tuple(estimate.X_WO), X_WO_true=pose_tuple(X_true),
                num_observed_points=int(len(observed)), posterior=posterior, views_used=int(estimate.views))
    if not plan.ok:
        timings["total"] = time.perf_counter() - t_all
        result = TransferResult(grasp_success=False, functional_success=False, failure_reason=plan.failure_reason,
                                detail=plan.status, object_rise_m=0.0, object_tilt_deg=0.0, timings=timings, **base)
        return (result, context) if return_context else result
    t0 = time.perf_counter()
    verdict, _, _, sim_time = simulate_and_judge(
        td.diagram, context, h, plan.timeline, spec, meshcat=td.meshcat, record_html=record_html,
        initialize_params=InitializeParams(suppress_initialization_events=True), on_phase=on_phase)
    timings["execute"] = time.perf_counter() - t0
    timings["simulated_s"] = sim_time
    timings["total"] = time.perf_counter() - t_all
    measured = {k: float(getattr(verdict, k)) for k in
                ("trigger_force_N", "in_hand_shift_m", "in_hand_turn_deg")}
    result = TransferResult(grasp_success=verdict.grasp_success, functional_success=verdict.functional_success,
                            failure_reason=verdict.failure_reason, detail=verdict.detail,
                            object_rise_m=float(verdict.object_rise_m), object_tilt_deg=float(verdict.tilt_deg),
                            timings=timings, judge=measured, **base)
    return (result, context) if return_context else result


def observe(scenario: Scenario, view: str = "single", camera: str | None = None, *, turn_deg: float = 0.0):
    """The object's cloud as the station's camera(s) see it: ``(points_W (N, 3), camera position or None)``.

    ``view`` "single": the scenario's camera (its position is returned for
    the visibility-aware fit), turned ``turn_deg`` about the vertical through
    its target when not 0 (:func:`turned_camera`: the further views of
    ``EXTRA_VIEW_AZIMUTHS_DEG``); "full": ``FULL_VIEW_CAMERAS`` ring cameras,
    clouds merged, no camera position. Renders once, simulates nothing.
    """
    if view not in ("single", "full"):
        raise InputError(f"view: expected 'single' or 'full', got {view!r}")
    if turn_deg:
        if view != "single":
            raise InputError(f"turn_deg: only the single view's camera can be turned, not the {view!r} view's")
        first = [c for c in scenario.cameras if c.name == (camera or scenario.cameras[0].name)]
        if not first:
            raise InputError(f"camera {camera!r} not in scenario {scenario.name!r}")
        scenario, camera = scenario.replace(cameras=(turned_camera(first[0], turn_deg),)), None
    if view == "full":
        scenario = scenario.replace(cameras=ring_cameras(scenario))
    station = make_station(scenario)
    context = station.CreateDefaultContext()
    names = [c.name for c in scenario.cameras] if view == "full" else [camera or scenario.cameras[0].name]
    clouds = [points_from_cloud(station.GetOutputPort(f"{n}.object_cloud_W").Eval(context)) for n in names]
    camera_W = None
    if view == "single":
        camera_W = station.GetOutputPort(f"{names[0]}.X_WC").Eval(context).translation()
    return np.vstack(clouds) if clouds else np.zeros((0, 3)), camera_W
