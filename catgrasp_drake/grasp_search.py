"""Search a category's grasp for robustness: cross-entropy over grasp variations, scored by simulated trials.

A candidate is a grasp variation (``catgrasp_drake.station.variation``: the
hand moved and turned about the functional region, the closed posture's
finger groups changed) of the category's hand-written grasp. Its score is
its *robustness* (``catgrasp_drake.grasping.robustness``): the mean score of
trials on the search instances, each under a seeded perturbation of the
object's pose, friction and mass. Trials are tasks of
:func:`catgrasp_drake.runner.run_tasks`: cached (an interrupted search
resumes), on local workers or Ray. The search runs on the committed
instances, or on imported objects (your own scan; a stretched copy of a committed instance, which is still
tuned-on data). The project's own grasps are searched on committed instances and their stretched copies only.

``apply_variation_to_spec`` turns the best variation back into a
hand-written grasp file (position, fingers, palm, posture overrides), so the
result is a reviewable diff of ``models/grasps/<category>_handwritten.yaml``.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from catgrasp_drake.core.fileio import file_sha256
from catgrasp_drake.data.dataset import object_files_sha256
from catgrasp_drake.errors import InputError
from catgrasp_drake.grasping.constraints import load_constraint
from catgrasp_drake.grasping.robustness import Robustness, perturbation, trial_score
from catgrasp_drake.grasping.search import CemParams, cem_maximize
from catgrasp_drake.robot.models import HAND_ACTUATED_JOINTS
from catgrasp_drake.station.variation import VARIATION_NAMES, VARIATION_SCALE, variation_dict, varied_posture

TASK = "grasp_search_trial"


def search_trial_task(spec: dict) -> dict:
    """Worker task: the category's hand-written grasp with a variation, on one instance under one perturbation."""
    from catgrasp_drake.station.handwritten import load_handwritten_motion
    from catgrasp_drake.station.scenario import load_scenario, with_instance
    from catgrasp_drake.station.variation import vary_motion
    from catgrasp_drake.trial import run_perturbed_trial

    category, instance, model_dir = spec["category"], spec["instance"], spec.get("model_dir")
    motion = load_handwritten_motion(category, instance, spec.get("grasp_file"), annotations_dir=model_dir)
    motion = vary_motion(motion, category, instance, spec["variation"], annotations_dir=model_dir)
    scenario = with_instance(load_scenario(f"{category}_default"), instance, category=category, model_dir=model_dir)
    return run_perturbed_trial(scenario, motion, spec["perturbation"])


SCREEN_TASK = "grasp_search_screen"


def screen_task(spec: dict) -> dict:
    """Worker task, no simulation: for each of ``spec["variations"]`` of the category's hand-written grasp, does
    the planner accept it on one object (``planning.fit.hand_fit``: the preshaped hand at the grasp pose against
    the true mesh, within the planner's clearance shift)? ``{"status": "ok", "plannable": [bool, ...]}``."""
    from catgrasp_drake.planning.fit import hand_fit
    from catgrasp_drake.station.handwritten import load_handwritten_motion
    from catgrasp_drake.station.scenario import load_scenario, with_instance
    from catgrasp_drake.station.variation import vary_motion

    category, instance, model_dir = spec["category"], spec["instance"], spec.get("model_dir")
    motion = load_handwritten_motion(category, instance, spec.get("grasp_file"), annotations_dir=model_dir)
    scenario = with_instance(load_scenario(f"{category}_default"), instance, category=category, model_dir=model_dir)
    plannable = [bool(hand_fit(scenario, vary_motion(motion, category, instance, v, annotations_dir=model_dir))
                      .plannable) for v in spec["variations"]]
    return {"status": "ok", "plannable": plannable}


@dataclass
class GraspSearchResult:
    """The search's best variation and its record (every candidate, trial and score)."""

    category: str
    instances: tuple[str, ...]
    best: dict  # variation name -> value
    best_score: float
    start_score: float
    rounds: list = field(default_factory=list)  # per round: [{"variation": {...}, "score": s, "trials": [...]}]
    trials: int = 0
    wall_s: float = 0.0
    screened: list = field(default_factory=list)  # per round, with a screen: {"drawn": n, "infeasible": m}

    def to_dict(self) -> dict:
        return asdict(self)


def search_grasp(category: str, instances, *, cem: CemParams = CemParams(), robustness: Robustness = Robustness(),
                 search_std=None, grasp_file: str | None = None, object_dirs=None,
                 cache_dir: str | None = "out/grasp_search/cache", workers: int | None = None, ray: str | None = None,
                 screen=None, screen_max_refused: int = 0, progress=None) -> GraspSearchResult:
    """Cross-entropy search of ``category``'s hand-written grasp (module docstring) on ``instances``.

    ``object_dirs``: ``{instance: directory}`` for instances that are imported objects (``catgrasp
    import-object``, a stretched copy of the stress split) rather than committed ones; their files are part of
    their trials' cache key.

    ``search_std``: the initial spread per variation parameter (default
    :data:`~catgrasp_drake.station.variation.VARIATION_SCALE`; 0 freezes a
    parameter). ``grasp_file``: the grasp to start from (default the category's
    ``models/grasps/<category>_handwritten.yaml``); its content is part of every trial's cache key.
    ``screen``: ``{object: directory or None}`` -- committed instances (None) or imported objects on which every
    candidate is first checked kinematically (:func:`screen_task`, no simulation, cached like the trials); a
    candidate the planner refuses on more than ``screen_max_refused`` of them is dropped and another drawn in its
    place (``cem_maximize``'s ``feasible``), so every round simulates a full population of candidates the planner
    accepts; only if the round's draws run out is a refused one kept, scored 0 and not simulated (its record
    lists where it was refused). The screen can hold many more objects than the search simulates on.
    ``progress(round, candidates, scores)`` after each round.
    """
    from catgrasp_drake.runner import code_fingerprint, run_tasks
    from catgrasp_drake.trial import TRIAL_CODE_PATHS

    instances = tuple(instances)
    if not instances:
        raise InputError("instances: the search needs at least one instance")
    object_dirs = dict(object_dirs or {})
    where = {i: {"model_dir": str(object_dirs[i]), "object_sha256": object_files_sha256(object_dirs[i], i)}
             for i in instances if i in object_dirs}
    std = VARIATION_SCALE if search_std is None else np.asarray(search_std, float)
    root = Path(__file__).resolve().parents[1]
    # what a search trial runs: the trial's code, this module's task and the grasp files it varies
    version = code_fingerprint([*TRIAL_CODE_PATHS, Path(__file__), root / "models" / "grasps"])
    perturbations = [(i, perturbation(robustness, i, k)) for i in instances for k in range(robustness.perturbations)]
    # a grasp file outside models/ is not in the code fingerprint: its content keys the trials
    start = {} if grasp_file is None else {"grasp_file": str(grasp_file), "grasp_sha256": file_sha256(grasp_file)}
    rounds = []
    t0 = time.perf_counter()

    screen = dict(screen or {})
    screen_where = {i: {"model_dir": str(d), "object_sha256": object_files_sha256(d, i)}
                    for i, d in screen.items() if d is not None}
    simulated = [0]

    screened: dict[tuple, list[str]] = {}  # candidate (rounded) -> the screen objects refusing it

    def refused_on(X: np.ndarray) -> list[list[str]]:
        """Per candidate, the screen objects on which the planner refuses it (each candidate screened once)."""
        keys = [tuple(round(float(x), 6) for x in v) for v in X]
        new = list(dict.fromkeys(k for k in keys if k not in screened))
        if screen and new:
            refused = {k: [] for k in new}
            specs = [start | screen_where.get(i, {}) | {"task": SCREEN_TASK, "category": category, "instance": i,
                                                        "variations": [list(k) for k in new]} for i in screen]
            for spec, o in zip(specs, run_tasks(screen_task, specs, cache_dir=cache_dir, code_version=version,
                                                workers=workers, ray_address=ray)):
                if o.result.get("status") != "ok":
                    raise InputError(f"screen: checking the grasp on {spec['instance']} failed: "
                                     f"{o.result.get('error')}")
                for k, ok in zip(new, o.result["plannable"]):
                    if not ok:
                        refused[k].append(spec["instance"])
            screened.update(refused)
        return [list(screened.get(k, [])) for k in keys]

    def feasible(X: np.ndarray) -> np.ndarray:
        return np.array([len(r) <= screen_max_refused for r in refused_on(X)])

    def evaluate(X: np.ndarray) -> np.ndarray:
        refused = refused_on(X)
        kept = [j for j in range(len(X)) if len(refused[j]) <= screen_max_refused]
        specs = [start | where.get(i, {}) | {"task": TASK, "category": category, "instance": i, "perturbation": p,
                                             "variation": [round(float(x), 6) for x in X[j]]}
                 for j in kept for i, p in perturbations]
        outcomes = run_tasks(search_trial_task, specs, cache_dir=cache_dir, code_version=version, workers=workers,
                             ray_address=ray)
        simulated[0] += len(specs)
        results = [o.result for o in outcomes]
        n = len(perturbations)
        scores = np.zeros(len(X))
        entries = []
        for j, v in enumerate(X):
            entry = {"variation": variation_dict(v), "score": 0.0}
            if screen:
                entry["screen_refused"] = refused[j]
            if j in kept:
                k = kept.index(j)
                trials = results[k * n:(k + 1) * n]
                scores[j] = float(np.mean([trial_score(t, robustness.grasp_weight) for t in trials]))
                entry["trials"] = [{"instance": s["instance"], "perturbation": s["perturbation"]} | t
                                   for s, t in zip(specs[k * n:(k + 1) * n], trials)]
            else:
                entry["trials"] = []  # refused by the screen: not simulated
            entries.append(entry | {"score": round(float(scores[j]), 4)})
        rounds.append(entries)
        return scores

    result = cem_maximize(evaluate, np.zeros(len(VARIATION_NAMES)), std, params=cem, on_round=progress,
                          feasible=feasible if screen else None)
    return GraspSearchResult(category=category, instances=instances, best=variation_dict(result.best),
                             best_score=result.best_score, start_score=float(result.scores[0][0]), rounds=rounds,
                             trials=simulated[0], wall_s=time.perf_counter() - t0, screened=result.draws)


def apply_variation_to_spec(spec: dict, variation: dict, category: str, postures: dict) -> dict:
    """The hand-written grasp ``spec`` (parsed YAML) with ``variation`` written into it.

    The variation turns the hand about the functional region's centre and moves it; in the spec's
    terms (position relative to the anchor = region centre + ``anchor.point``): position' =
    R (point + position) + d - point, fingers' = R fingers, palm' = R palm. The closed posture's
    changed joints become ``posture_overrides.closed`` (absolute angles, rad). ``postures`` is the
    spec's posture set (``load_hand_postures``).
    """
    if spec.get("anchor", {}).get("region") != load_constraint(category).region:
        raise InputError(f"spec: the grasp must be anchored on the {load_constraint(category).region} region")
    v = np.array([float(variation.get(n, 0.0)) for n in VARIATION_NAMES])
    R = Rotation.from_euler("xyz", v[3:6], degrees=True).as_matrix()
    point = np.asarray(spec["anchor"].get("point", (0.0, 0.0, 0.0)), float)
    g = dict(spec["grasp"])
    position = R @ (point + np.asarray(g["position"], float)) + v[:3] - point
    g["position"] = [round(float(x), 5) for x in position]
    g["fingers"] = [round(float(x), 5) for x in R @ np.asarray(g["fingers"], float)]
    g["palm"] = [round(float(x), 5) for x in R @ np.asarray(g["palm"], float)]
    out = dict(spec) | {"grasp": g}
    closed = np.array(postures["closed"], float)
    overrides = dict((spec.get("posture_overrides") or {}).get("closed", {}))
    for joint, value in overrides.items():
        closed[HAND_ACTUATED_JOINTS.index(joint)] = float(value)
    new = varied_posture(closed, v)
    for joint, q0, q1 in zip(HAND_ACTUATED_JOINTS, closed, new):
        if abs(q1 - q0) > 1e-9:
            overrides[joint] = round(float(q1), 4)
    if overrides:
        out["posture_overrides"] = dict(spec.get("posture_overrides") or {}) | {"closed": overrides}
    return out
