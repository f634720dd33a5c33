"""One grasp trial: plan, simulate approach -> reach -> close -> lift -> hold -> shake -> press, judge.

``run_grasp_trial(scenario, motion_O)`` places the object with the
scenario's pose, expresses the motion (object frame) in the world, plans it
(:func:`catgrasp_drake.planning.planner.plan_grasp`), simulates
it and judges it (:mod:`catgrasp_drake.station.judge`). It returns a frozen
:class:`TrialResult` and never raises for a failed grasp: unreachable poses,
collisions and simulation errors end up in ``failure_reason``/``detail``.

The trial diagram (station + :class:`~catgrasp_drake.systems.grasp_execution.PlanPlayback`) is built once per
scenario and process and reused (the plan is a context parameter), so the
object and robot files are parsed once; with ``meshcat`` a fresh diagram is
built (the visualizer belongs to it). Every trial starts from a fresh
default context, so the same inputs give the same result.
"""

from __future__ import annotations

import time
from collections import OrderedDict
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np
from pydrake.geometry import Meshcat
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder, EventStatus

from catgrasp_drake.core.fileio import atomic_write_text
from catgrasp_drake.errors import InputError
from catgrasp_drake.grasping.motion import GraspMotion
from catgrasp_drake.grasping.robustness import object_offset
from catgrasp_drake.planning.model import PlanningModel
from catgrasp_drake.planning.records import GraspPlan, PlanParams, hold_plan
from catgrasp_drake.robot.models import HAND_BASE_LINK, INDEX_DISTAL_LINK, load_hand_postures
from catgrasp_drake.runner import code_fingerprint
from catgrasp_drake.station.builder import StationHandles, add_station, apply_context_knobs, posture_category
from catgrasp_drake.station.judge import (
    ContactRecord,
    FirstMove,
    JudgeSpec,
    Snapshot,
    Verdict,
    decided_failure,
    has_moved,
    judge,
    object_partners,
)
from catgrasp_drake.station.scenario import Scenario
from catgrasp_drake.systems.grasp_execution import PlanPlayback

_ROOT = Path(__file__).resolve().parents[1]
#: Files whose contents decide a trial's outcome: trial caches (training, grasp search) are keyed by
#: their hash (``runner.code_fingerprint``: contents, not paths).
TRIAL_CODE_PATHS = (
    _ROOT / "catgrasp_drake" / "station",
    _ROOT / "catgrasp_drake" / "planning",
    _ROOT / "catgrasp_drake" / "systems" / "grasp_execution.py",
    _ROOT / "catgrasp_drake" / "trial.py",
    _ROOT / "catgrasp_drake" / "robot",
    _ROOT / "catgrasp_drake" / "grasping" / "motion.py",
    _ROOT / "catgrasp_drake" / "grasping" / "robustness.py",
    _ROOT / "models" / "svh",
    _ROOT / "models" / "ur10",
    _ROOT / "models" / "station.scenarios.yaml",
    _ROOT / "models" / "objects",
)


def trial_code_version() -> str:
    """The fingerprint of :data:`TRIAL_CODE_PATHS`."""
    return code_fingerprint(TRIAL_CODE_PATHS)


#: Hydroelastic patches contribute at most this many points (centroid + face centroids).
MAX_POINTS_PER_PATCH = 64


@dataclass(frozen=True)
class TrialResult:
    """Outcome of one grasp trial (see ``catgrasp_drake.station.judge`` for the rules)."""

    scenario: str
    category: str | None
    instance: str | None
    grasp_success: bool
    functional_success: bool
    failure_reason: str | None
    detail: str
    plan_status: str
    timeline: dict
    X_WO_initial: tuple
    X_WO_final: tuple  # 4x4 as nested tuples
    object_rise_m: float
    object_tilt_deg: float
    contacts_end: tuple  # ((body_a, body_b), ...) sorted, at the end of the trial (after the press)
    hand_links_on_object: tuple  # hand links touching the object at the end of the trial
    sim_time_s: float
    wall_time_s: float
    plan_time_s: float
    # what the judge measured (None: not measured, e.g. no plan, no trigger contact)
    trigger_force_N: float | None = None  # index distal on the trigger, along its travel, end of the press
    in_hand_shift_m: float | None = None  # largest object motion relative to the hand (vs start of the hold)
    in_hand_turn_deg: float | None = None
    object_shift_mm: float | None = None  # how far the planner's object clearance moved the grasp (mm; 0: clear)

    @property
    def realtime_rate(self) -> float:
        return self.sim_time_s / self.wall_time_s if self.wall_time_s > 0 else 0.0

    def outcome(self) -> dict:
        """Everything but the timings (deterministic for the same inputs)."""
        d = asdict(self)
        for k in ("wall_time_s", "plan_time_s"):
            d.pop(k)
        return d

    def to_dict(self) -> dict:
        d = asdict(self)
        d["realtime_rate"] = self.realtime_rate
        return d


# ----------------------------------------------------------------------------- contacts
def _body_name(plant, body) -> str:
    return f"{plant.GetModelInstanceName(body.model_instance())}::{body.name()}"


def contacts_from_results(plant, inspector, results) -> tuple[ContactRecord, ...]:
    """ContactRecords (sorted by body names) from a ``ContactResults`` value.

    ``force_on_a_W`` is the contact force on ``body_a`` (hydroelastic: the
    translational part of ``F_Ac_W``, the spatial force on body A at the patch
    centroid; point pair: minus ``contact_force()``, which is on body B).
    """
    out = []
    for i in range(results.num_hydroelastic_contacts()):
        info = results.hydroelastic_contact_info(i)
        s = info.contact_surface()
        a = plant.GetBodyFromFrameId(inspector.GetFrameId(s.id_M()))
        b = plant.GetBodyFromFrameId(inspector.GetFrameId(s.id_N()))
        mesh = s.tri_mesh_W() if s.is_triangle() else s.poly_mesh_W()
        n = mesh.num_elements()
        idx = np.linspace(0, n - 1, min(n, MAX_POINTS_PER_PATCH - 1)).astype(int) if n else []
        pts = [tuple(np.asarray(s.centroid(), float))] + [tuple(np.asarray(mesh.element_centroid(int(e)), float))
                                                          for e in idx]
        f_A = np.asarray(info.F_Ac_W().translational(), float)  # on body A (geometry M's body)
        out.append(ContactRecord(_body_name(plant, a), _body_name(plant, b), tuple(pts), float(np.linalg.norm(f_A)),
                                 "hydroelastic", tuple(f_A)))
    for i in range(results.num_point_pair_contacts()):
        info = results.point_pair_contact_info(i)
        a = plant.get_body(info.bodyA_index())
        b = plant.get_body(info.bodyB_index())
        f_B = np.asarray(info.contact_force(), float)  # on body B
        out.append(ContactRecord(_body_name(plant, a), _body_name(plant, b),
                                 (tuple(np.asarray(info.contact_point(), float)),),
                                 float(np.linalg.norm(f_B)), "point", tuple(-f_B)))
    # one orientation per pair (the force vector stays on its body), deterministic order
    norm = [c.swapped() if c.body_b < c.body_a else c for c in out]
    return tuple(sorted(norm, key=lambda c: (c.body_a, c.body_b, c.kind, -c.force_N)))


# ----------------------------------------------------------------------------- trial diagram
@dataclass
class TrialDiagram:
    """A built station + plan playback, reusable across trials of one scenario."""

    diagram: object
    station: StationHandles
    generator: PlanPlayback
    meshcat: Meshcat | None = None


def build_trial_diagram(scenario: Scenario, meshcat: Meshcat | None = None) -> TrialDiagram:
    """Station + ``PlanPlayback`` (holding the start pose until a plan is set)."""
    builder = DiagramBuilder()
    h = add_station(builder, scenario, meshcat)
    q_open = load_hand_postures(posture_category(scenario))["open"]
    generator = builder.AddNamedSystem("grasp_trajectory", PlanPlayback(
        h.plant, h.arm, h.hand, hold_plan(np.asarray(scenario.arm_q_home), q_open, "no plan")))
    builder.Connect(generator.GetOutputPort("arm_desired_state"), h.plant.get_desired_state_input_port(h.arm))
    builder.Connect(generator.GetOutputPort("hand_desired_state"), h.plant.get_desired_state_input_port(h.hand))
    diagram = builder.Build()
    diagram.set_name("grasp_trial")
    return TrialDiagram(diagram, h, generator, meshcat)


_CACHE: "OrderedDict[Scenario, TrialDiagram]" = OrderedDict()
_CACHE_SIZE = 4


def trial_diagram(scenario: Scenario, meshcat: Meshcat | None = None) -> TrialDiagram:
    """The (per-process cached, when ``meshcat`` is None) trial diagram of ``scenario``."""
    if meshcat is not None:
        return build_trial_diagram(scenario, meshcat)
    td = _CACHE.get(scenario)
    if td is None:
        td = build_trial_diagram(scenario)
        _CACHE[scenario] = td
        while len(_CACHE) > _CACHE_SIZE:
            _CACHE.popitem(last=False)
    else:
        _CACHE.move_to_end(scenario)
    return td


def judge_spec(station: StationHandles, lift_height: float) -> JudgeSpec:
    """The judge's view of ``station``: model names, the object's annotated regions, the lift height (m)."""
    plant = station.plant
    scenario = station.scenario
    regions = scenario.object.annotations().get("regions", {})
    return JudgeSpec(
        object_model=plant.GetModelInstanceName(station.object_instance),
        hand_model=station.hand_name,
        arm_model=station.arm_name,
        table_model=plant.GetModelInstanceName(station.table),
        index_distal_body=f"{station.hand_name}::{INDEX_DISTAL_LINK}",
        category=scenario.object.category,
        regions=regions,
        lift_height=lift_height,
    )


def plan_for(td: TrialDiagram, motion_W: GraspMotion, params: PlanParams = PlanParams()) -> GraspPlan:
    """Plan ``motion_W`` (world frame) on a scratch context of the trial diagram (true object as the obstacle)."""
    return PlanningModel.of_station(td.diagram, td.station).plan(motion_W, params)


# ----------------------------------------------------------------------------- the trial
def station_snapshot(h: StationHandles, context) -> Snapshot:
    """The object's pose, the hand base pose and all contacts in the root ``context`` of a diagram holding ``h``."""
    plant_ctx = h.plant.GetMyContextFromRoot(context)
    X_WO = h.plant.EvalBodyPoseInWorld(plant_ctx, h.object_body).GetAsMatrix4()
    X_WH = h.plant.EvalBodyPoseInWorld(plant_ctx, h.plant.GetBodyByName(HAND_BASE_LINK, h.hand)).GetAsMatrix4()
    results = h.plant.get_contact_results_output_port().Eval(plant_ctx)
    contacts = contacts_from_results(h.plant, h.scene_graph.model_inspector(), results)
    return Snapshot(context.get_time(), X_WO, contacts, X_WH)


class FirstMoveWatch:
    """Watches the object from the start of a trial to ``until`` (s): the first instant it moved
    (:data:`~catgrasp_drake.station.judge.FIRST_MOVE_TILT_DEG`, :data:`~catgrasp_drake.station.judge.FIRST_MOVE_SHIFT_M`
    from ``X_WO_start``) and whether a robot body (hand or arm) touched it then, as a
    :class:`~catgrasp_drake.station.judge.FirstMove` (``first``; None until it moves). ``update`` is called by the
    simulator's monitor after every step; it reads the object's pose, and the contacts once, at the first move."""

    def __init__(self, h: StationHandles, until: float):
        self._h, self._until = h, float(until)
        self.X_WO_start: np.ndarray | None = None
        self.first: FirstMove | None = None

    def update(self, context) -> None:
        if self.X_WO_start is None or self.first is not None or context.get_time() > self._until:
            return
        h = self._h
        X_WO = h.plant.EvalBodyPoseInWorld(h.plant.GetMyContextFromRoot(context), h.object_body).GetAsMatrix4()
        if not has_moved(self.X_WO_start, X_WO):
            return
        obj = h.plant.GetModelInstanceName(h.object_instance)
        partners = object_partners(station_snapshot(h, context).contacts, obj)
        self.first = FirstMove(round(context.get_time(), 6), bool(partners & {h.hand_name, h.arm_name}))


def _finite_or_none(value: float, digits: int = 6) -> float | None:
    """``value`` rounded, or None for nan (keeps ``TrialResult.outcome()`` comparable and JSON-clean)."""
    return round(float(value), digits) if np.isfinite(value) else None


def pose_tuple(X: np.ndarray) -> tuple:
    """A pose (4x4) as nested tuples rounded to 1e-9 (comparable, JSON-able records)."""
    return tuple(tuple(round(float(v), 9) for v in row) for row in np.asarray(X))


def run_grasp_trial(scenario: Scenario, motion_O: GraspMotion, *, meshcat: Meshcat | None = None,
                    record_html: str | Path | None = None, params: PlanParams = PlanParams(),
                    on_phase=None, instants=None, stop_when_decided: bool | None = None) -> TrialResult:
    """Execute ``motion_O`` (hand control poses in the OBJECT frame) on the scenario's object.

    With ``meshcat`` the run is recorded on it (MeshcatVisualizer recording);
    with ``record_html`` as well, the recording is written there as one
    self-contained HTML file. ``on_phase(label, root_context)`` is called
    at the phases of the motion, or at ``instants``; ``stop_when_decided``: end
    the run where a failure is decided (default: when nothing watches it), both as
    in :func:`simulate_and_judge`. Returns a :class:`TrialResult`; never raises for a failed grasp.
    """
    if not isinstance(motion_O, GraspMotion):
        raise InputError(f"motion_O: expected a GraspMotion, got {type(motion_O).__name__}")
    if motion_O.frame != "object":
        raise InputError("motion_O: expected poses in the object frame (GraspMotion.frame == 'object')")
    if record_html is not None and meshcat is None:
        raise InputError("record_html needs a meshcat (the recording is made on it)")
    wall0 = time.perf_counter()
    td = trial_diagram(scenario, meshcat)
    X_WO0 = scenario.X_WO()
    motion_W = motion_O.in_world(X_WO0)
    spec = judge_spec(td.station, motion_O.lift_height)
    plan = plan_for(td, motion_W, params)

    def result(verdict: Verdict, X_final, snapshot_end: Snapshot | None, sim_time: float) -> TrialResult:
        contacts = snapshot_end.contacts if snapshot_end else ()
        pairs = tuple(sorted({(c.body_a, c.body_b) for c in contacts}))
        hand_links = tuple(sorted({c.other(spec.object_model).split("::", 1)[1] for c in contacts
                                   if c.involves(spec.object_model) and c.involves(spec.hand_model)}))
        return TrialResult(
            scenario=scenario.name, category=scenario.object.category, instance=scenario.object.instance,
            grasp_success=verdict.grasp_success, functional_success=verdict.functional_success,
            failure_reason=verdict.failure_reason, detail=verdict.detail, plan_status=plan.status,
            timeline=plan.timeline.as_dict(), X_WO_initial=pose_tuple(X_WO0), X_WO_final=pose_tuple(X_final),
            object_rise_m=round(verdict.object_rise_m, 9), object_tilt_deg=round(verdict.tilt_deg, 6),
            contacts_end=pairs, hand_links_on_object=hand_links, sim_time_s=sim_time,
            wall_time_s=time.perf_counter() - wall0, plan_time_s=plan.solve_time_s,
            trigger_force_N=_finite_or_none(verdict.trigger_force_N),
            in_hand_shift_m=_finite_or_none(verdict.in_hand_shift_m),
            in_hand_turn_deg=_finite_or_none(verdict.in_hand_turn_deg),
            object_shift_mm=round(1000.0 * float(np.linalg.norm(plan.object_shift)), 3))

    if not plan.ok:
        return result(Verdict(False, False, plan.failure_reason, plan.status), X_WO0, None, 0.0)

    context = td.diagram.CreateDefaultContext()
    td.generator.set_plan(td.generator.GetMyMutableContextFromRoot(context), plan)
    verdict, X_final, end, sim_time = simulate_and_judge(td.diagram, context, td.station, plan.timeline, spec,
                                                         meshcat=meshcat, record_html=record_html,
                                                         on_phase=on_phase, instants=instants,
                                                         stop_when_decided=stop_when_decided)
    return result(verdict, X_final, end, sim_time)


#: Wall-clock limit (s) of one simulated grasp: a contact problem that stalls the solver ends as
#: a failed trial ("simulation_timeout") instead of blocking a training or evaluation run. A
#: normal trial takes 3-15 s on one core; the limit is 20x that so that a loaded machine does not
#: change outcomes (at 90 s, a run of the test suite beside a 2-worker evaluation timed a trial out).
MAX_TRIAL_WALL_S = 300.0


def phase_instants(timeline) -> tuple[tuple[str, float], ...]:
    """The instants a film of the trial shows, ``(label, t)`` in time order: the start of every phase of
    the plan's ``timeline`` (``approach`` ... ``press``), the middle of the closing and the end."""
    d = timeline.as_dict()
    marks = [(name, float(t)) for name, t in d.items() if name != "settle"]
    marks.append(("closing", 0.5 * (float(d["close"]) + float(d["lift"]))))
    return tuple(sorted(marks, key=lambda m: m[1]))


def simulate_and_judge(diagram, context, station: StationHandles, timeline, spec: JudgeSpec, *,
                       meshcat: Meshcat | None = None, record_html=None, initialize_params=None,
                       max_wall_s: float = MAX_TRIAL_WALL_S, on_phase=None, instants=None,
                       stop_when_decided: bool | None = None):
    """Simulate ``diagram`` from ``context`` to ``timeline.end`` and judge the grasp.

    Snapshots are taken at the start, at ``timeline.close``, ``timeline.hold``
    (end of the lift), ``timeline.shake`` (end of the hold),
    ``timeline.press`` (end of the shake) and ``timeline.end`` (end of the
    press). A solver failure inside the plant becomes a
    ``simulation_error`` verdict, never an exception. With the station's
    Meshcat visualizer the run is recorded (and written to ``record_html``).
    Past ``max_wall_s`` seconds of wall-clock time the run stops with a
    ``simulation_timeout`` verdict.
    With ``on_phase`` (a callable ``on_phase(label, context)``) the run also
    stops at every instant of :func:`phase_instants` -- or of ``instants``,
    ``(label, t)`` pairs in time order -- and calls it there (a film, a trace;
    the simulated motion is the same: the plant's updates are periodic).
    ``stop_when_decided``: stop at the first snapshot after which the judge's
    verdict is a decided failure (:func:`~catgrasp_drake.station.judge.decided_failure`:
    knocked away before closing, not lifted or dropped by the end of the hold,
    shaken loose) -- the same success flags, reason and detail as the full run,
    with the object's rise, tilt and final pose measured where the run stopped.
    None (default): stop only when nothing watches the run (no ``on_phase``, no
    Meshcat recording); a film or a recording shows the whole motion.
    Returns ``(verdict, X_WO_final, end_snapshot or None, simulated_time_s)``;
    the "end" snapshot is the last one taken.
    """
    apply_context_knobs(station, context)
    simulator = Simulator(diagram, context)
    if on_phase is None:
        instants = []
    else:
        instants = list(phase_instants(timeline) if instants is None else instants)

    def advance_to(t: float) -> None:
        while instants and instants[0][1] <= t:
            label, t_mark = instants.pop(0)
            simulator.AdvanceTo(max(t_mark, context.get_time()))
            on_phase(label, context)
        simulator.AdvanceTo(max(float(t), context.get_time()))

    simulator.set_target_realtime_rate(0.0)
    deadline = time.monotonic() + float(max_wall_s)

    watch = FirstMoveWatch(station, timeline.close)

    def monitor(root_context):
        if time.monotonic() > deadline:
            return EventStatus.Failed(None, f"wall-clock limit of {max_wall_s:.0f} s reached")
        watch.update(root_context)
        return EventStatus.Succeeded()

    simulator.set_monitor(monitor)
    visualizer = station.meshcat_visualizer
    if stop_when_decided is None:
        stop_when_decided = on_phase is None and visualizer is None
    early = None
    if visualizer is not None:
        visualizer.DeleteRecording()
        visualizer.StartRecording(False)
    try:
        if initialize_params is None:
            simulator.Initialize()
        else:
            simulator.Initialize(initialize_params)
        initial = station_snapshot(station, context)
        watch.X_WO_start = initial.X_WO
        if on_phase is not None:
            on_phase("start", context)
        advance_to(timeline.close)
        before_close = replace(station_snapshot(station, context), first_move=watch.first)
        snapshots = []
        for t in (timeline.hold, timeline.shake, timeline.press, timeline.end):
            if stop_when_decided:
                early = decided_failure(spec, initial, before_close, *snapshots)
                if early is not None:
                    break
            advance_to(t)
            snapshots.append(station_snapshot(station, context))
    except RuntimeError as e:  # a solver failure inside the plant: report, never raise
        X = station.plant.EvalBodyPoseInWorld(station.plant.GetMyContextFromRoot(context),
                                              station.object_body).GetAsMatrix4()
        message = str(e).splitlines()[0][:200] if str(e) else type(e).__name__
        reason = "simulation_timeout" if "wall-clock limit" in str(e) else "simulation_error"
        return Verdict(False, False, reason, message), X, None, context.get_time()
    finally:
        if visualizer is not None:
            visualizer.StopRecording()
            visualizer.PublishRecording()
            if record_html is not None and meshcat is not None:
                atomic_write_text(record_html, meshcat.StaticHtml())
    if early is not None:
        last = snapshots[-1] if snapshots else before_close
        return early, last.X_WO, last, context.get_time()
    verdict = judge(spec, initial, before_close, *snapshots)
    end = snapshots[-1]
    return verdict, end.X_WO, end, context.get_time()


def run_perturbed_trial(scenario: Scenario, motion_O: GraspMotion, perturbation: dict) -> dict:
    """``motion_O`` (object frame, planned for the scenario's object) executed on an object perturbed by
    ``perturbation`` (:func:`catgrasp_drake.grasping.robustness.perturbation`: pose offset, friction,
    mass factor). Returns the compact, JSON-able outcome a robustness score is computed from."""
    scenario = scenario.replace(plant=replace(scenario.plant, object_friction=perturbation["friction"],
                                              object_mass_scale=perturbation["mass_scale"]))
    E = object_offset(perturbation)
    r = run_grasp_trial(scenario, replace(motion_O, poses=np.linalg.inv(E) @ motion_O.poses))
    return {"grasp": bool(r.grasp_success), "functional": bool(r.functional_success), "reason": r.failure_reason,
            "tilt_deg": round(float(r.object_tilt_deg), 3), "trigger_force_N": r.trigger_force_N,
            "sim_s": round(float(r.sim_time_s), 3), "wall_s": round(float(r.wall_time_s), 3)}
