"""The training phase (paper, Algorithm 1): from a category's instances to a CategoryModel.

1. Full clouds of the instances (ray-casting + voxel grid), CPD from the
   canonical shape to each, PCA-EM -> shape space (``core.shape_space``).
2. The canonical grasping motion: the category's hand-written grasp
   (``models/grasps/<category>_handwritten.yaml``) on the canonical instance.
3. For each training instance: warp the canonical motion onto it with its CPD
   field W_i (at the grasp's functional point -- the canonical trigger or
   handle centre, fixed in the hand -- the hand rigid about it, turned by the
   field's rotation averaged over 5 cm),
   sample motions around it (``grasping.sampling``: translation
   ~ N(0, 1.5 cm) <= 4 cm, Shoemake rotations <= 0.2 rad about the grasp
   functional point; sample 0 is the
   warped motion itself), drop those violating the functional constraint
   (``grasping.constraints``, judged with the instance's annotations), run
   the rest as grasp trials in the station (``catgrasp_drake.trial``; motions whose
   arm plan collides or is unreachable are rejected there before any
   simulation), in parallel worker processes with an on-disk cache
   (``runner``).
4. Map every functional success back into the canonical frame with the
   inverse deformation (eq. 14; rotations re-orthonormalised), flatten to
   descriptors and fit the ridge regressor latent x -> descriptor, each
   instance weighted equally whatever its number of successes.

With ``TrainingConfig.search`` (:class:`InstanceSearch`), step 3 is a
per-instance grasp search instead of random samples: a cross-entropy search
(``grasping.search.CemSearch``) over grasp variations
(``station.variation``: the hand moved and turned about the warped
functional point, the closed posture's finger groups changed) of the warped
canonical motion, every candidate scored by its robustness
(``grasping.robustness``: trials under seeded perturbations of the object's
pose, friction and mass). All instances' searches run in lockstep, one batch
of cached trials per round, on local workers or Ray. Each instance keeps its
best ``keep`` candidates with at least one functional trial, weighted by
their score; the regressor is then ``regressor`` -- ``"auto"`` chooses among
mean, nearest instance, ridge and kernel ridge by leave-one-instance-out
error at the functional point (``core.regression.select_regressor``),
``"trials"`` among those and the canonical grasp itself by leave-one-instance-out
grasp trials (:func:`choose_regressor_by_trials`).

A new category from a folder of meshes (``data.category_folder``) is trained
by :func:`train_category_folder`: its meshes imported, then this on them alone.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.core.deformation import deform_points, inverse_warp_poses, warp_poses
from catgrasp_drake.core.regression import (
    REGRESSOR_GRID,
    SIMPLICITY,
    LinearRegressor,
    choose_regressor,
    fit_ridge,
    instance_means,
    score_regressors,
    simplest_within_one_se,
)
from catgrasp_drake.core.shape_space import build_shape_space
from catgrasp_drake.data.category_folder import import_category, read_category_folder
from catgrasp_drake.data.dataset import (
    imported_object,
    instance_clouds,
    list_instances,
    load_annotations,
    read_annotations,
)
from catgrasp_drake.data.meshes import read_mesh
from catgrasp_drake.data.pointclouds import full_cloud
from catgrasp_drake.errors import InputError
from catgrasp_drake.grasping.constraints import load_constraint
from catgrasp_drake.grasping.descriptor import descriptor_vector, functional_point, motion_from_descriptor
from catgrasp_drake.grasping.motion import GraspMotion
from catgrasp_drake.grasping.robustness import Robustness, perturbation, trial_score
from catgrasp_drake.grasping.sampling import SamplingParams, perturb_poses, perturbations
from catgrasp_drake.grasping.search import CemParams, CemSearch
from catgrasp_drake.runner import run_tasks
from catgrasp_drake.station.handwritten import load_handwritten_motion
from catgrasp_drake.station.scenario import load_scenario
from catgrasp_drake.station.variation import VARIATION_SCALE, variation_dict, vary_motion_about
from catgrasp_drake.trial import run_grasp_trial, run_perturbed_trial, trial_code_version


@dataclass(frozen=True)
class InstanceSearch:
    """Per-instance grasp search of training (module docstring). Trials per instance: at most
    ``cem.rounds * cem.population * robustness.perturbations`` (candidates that break the functional
    constraint, or whose plan is refused, cost no simulation)."""

    cem: CemParams = CemParams(rounds=3, population=8, elite=2)
    robustness: Robustness = Robustness(perturbations=2)
    keep: int = 3  # best candidates kept per instance
    spread: float = 1.0  # the search's initial spread, times station.variation.VARIATION_SCALE

    def __post_init__(self):
        if not (isinstance(self.keep, int) and self.keep >= 1):
            raise InputError(f"keep: expected a positive integer, got {self.keep!r}")
        if not self.spread > 0:
            raise InputError(f"spread: expected > 0, got {self.spread!r}")


#: How the latent -> grasp regressor is chosen: "ridge" (fixed ``ridge_alpha``), "auto" (leave-one-instance-out
#: error at the functional point, :func:`fit_grasp_regressor`), "trials" (leave-one-instance-out grasp trials,
#: :func:`choose_regressor_by_trials`).
REGRESSOR_CHOICES = ("ridge", "auto", "trials")


@dataclass(frozen=True)
class TrainingConfig:
    """Parameters of :func:`train_category` (SI units)."""

    samples_per_instance: int = 12
    sampling: SamplingParams = SamplingParams()
    seed: int = 0
    # None: the first instance; "region": the one whose functional region the CPD fields carry best onto
    # the others (choose_canonical_by_region)
    canonical_instance: str | None = None
    cloud_voxel: float = 0.01
    # CPD kernel width (m). 0.10, not the core's 0.02: a smooth field keeps correspondences coherent
    # where grasps need them -- the canonical trigger/handle warped onto each training instance lands
    # 3.8 / 4.3 / 4.0 mm from the annotated one (drill / spray bottle / mug) vs 19.0 / 18.4 / 5.9 mm at
    # 0.02, for a registration Chamfer of 2.8 vs 2.1 mm (drills; benchmarks/bench_grasp_warp.py).
    beta: float | None = 0.10
    lam: float | None = None
    variance: float = 0.95
    # leave-one-instance-out on the drills: 13.0 mm (1.0) vs 26.6 mm (0.01) at the functional point
    # (benchmarks/bench_grasp_warp.py)
    ridge_alpha: float = 1.0
    grasp_rotation_radius: float = 0.05  # m; see CategoryModel.grasp_rotation_radius
    search: InstanceSearch | None = None  # None: samples_per_instance random samples (the paper)
    grasp_file: str | None = None  # the canonical grasp; None: models/grasps/<category>_handwritten.yaml
    regressor: str = "ridge"  # REGRESSOR_CHOICES: "ridge" (with ridge_alpha), "auto" or "trials"
    workers: int | None = None  # None: all cores
    cache_dir: str | None = "out/trial_cache"
    ray: str | None = None  # Ray address ("auto", "local", "host:port") or None: local worker processes

    def __post_init__(self):
        if self.regressor not in REGRESSOR_CHOICES:
            raise InputError(f"regressor: expected one of {', '.join(REGRESSOR_CHOICES)}, got {self.regressor!r}")

    def shape_kwargs(self) -> dict:
        kw = {"variance": self.variance}
        if self.beta is not None:
            kw["beta"] = self.beta
        if self.lam is not None:
            kw["lam"] = self.lam
        return kw


def _task_scenario(spec: dict):
    """The spec's scenario with its object: an embedded instance, or an imported one (``model_dir``)."""
    base = load_scenario(spec["scenario"])
    obj = dataclasses.replace(base.object, category=spec["category"], instance=spec["instance"])
    if spec.get("model_dir") is not None:
        obj = dataclasses.replace(obj, primitive=None, model_dir=spec["model_dir"])
    return base.replace(name=f"{spec['scenario']}:{spec['instance']}", object=obj)


def grasp_trial_task(spec: dict) -> dict:
    """Worker task: one grasp trial of ``spec["motion"]`` (object frame) on one instance."""
    return run_grasp_trial(_task_scenario(spec), GraspMotion.from_dict(spec["motion"])).to_dict()


def robust_trial_task(spec: dict) -> dict:
    """Worker task: ``spec["motion"]`` (object frame) on one instance under ``spec["perturbation"]``."""
    return run_perturbed_trial(_task_scenario(spec), GraspMotion.from_dict(spec["motion"]), spec["perturbation"])


def _object_key(name: str, object_dirs) -> dict:
    """A trial spec's object: the instance, and the folder of an imported one (embedded: no extra key,
    so their cache keys are what they always were)."""
    return {"instance": name} | ({"model_dir": object_dirs[name]} if name in object_dirs else {})


@dataclass
class InstanceStats:
    sampled: int = 0
    rejected_constraint: int = 0
    rejected_plan: int = 0
    simulated: int = 0
    grasped: int = 0
    functional: int = 0
    errors: int = 0


@dataclass
class _Candidate:
    instance_index: int
    sample: int
    motion: GraspMotion


def functional_point_in_hand(template: GraspMotion, annotations: dict, region: str) -> np.ndarray:
    """The canonical instance's functional region centre (trigger, handle) in the hand frame H at the grasp (m).

    This point, fixed in the hand, is the grasp's anchor: it is what the
    deformation warps (the hand rigid about it) and what the functional
    constraint keeps near the instance's region.
    """
    regions = annotations.get("regions", {})
    if region not in regions:
        raise InputError(f"the canonical instance has no {region!r} region annotated; regions: {sorted(regions)}")
    X = template.pose("grasp")
    return X[:3, :3].T @ (np.asarray(regions[region]["center"], float) - X[:3, 3])


def warped_start(space, i: int, template: GraspMotion, tip_H, config) -> tuple[np.ndarray, np.ndarray]:
    """The canonical motion's control poses warped onto training instance ``i`` (instance frame) and the
    grasp's functional point on it (m): where sampling and the search start, and what they turn about."""
    ref = warp_poses(space.canonical, space.W_train[i], space.beta, template.poses, anchor=tip_H,
                     rotation_radius=config.grasp_rotation_radius)
    k = template.pose_names.index("grasp")
    return ref, ref[k, :3, :3] @ tip_H + ref[k, :3, 3]


def _tally(st: InstanceStats, *, error: bool, reason, sim_s: float, grasp: bool, functional: bool) -> bool:
    """Count one trial outcome in ``st``; True if it was simulated (not an error, not a refused plan)."""
    if error:
        st.errors += 1
    elif reason in ("unreachable", "collision_before_closing") and sim_s == 0:
        st.rejected_plan += 1
    else:
        st.simulated += 1
        st.grasped += bool(grasp)
        st.functional += bool(functional)
        return True
    return False


def sample_training_motions(category, space, instances, template, config, annotations, tip_H):
    """Warped + perturbed motions per instance, filtered by the functional constraint."""
    constraint = load_constraint(category)
    stats = {name: InstanceStats() for name in instances}
    candidates: list[_Candidate] = []
    grasp_k = template.pose_names.index("grasp")
    for i, name in enumerate(instances):
        ref, centre = warped_start(space, i, template, tip_H, config)  # perturbed about the grasp centre
        rng = np.random.default_rng([config.seed, i])
        T = perturbations(rng, config.samples_per_instance, config.sampling)
        T[0] = np.eye(4)  # sample 0: the warped canonical motion itself
        regions = annotations[name].get("regions", {})
        for k in range(config.samples_per_instance):
            poses = perturb_poses(ref, T[k], centre)
            stats[name].sampled += 1
            ok, _ = constraint.check(poses[grasp_k], ref[grasp_k], regions, tip_H)
            if not ok:
                stats[name].rejected_constraint += 1
                continue
            motion = GraspMotion(poses, template.pose_names, dict(template.postures), "object",
                                 template.lift_height, template.hold_time)
            candidates.append(_Candidate(i, k, motion))
    return candidates, stats


@dataclass
class _Kept:
    """A grasp kept as knowledge of one training instance: its motion (instance frame) and weight."""

    instance_index: int
    motion: GraspMotion
    weight: float


def search_training_grasps(category, space, instances, template, config, annotations, tip_H, progress=None,
                           object_dirs=()):
    """Training's per-instance grasp search (module docstring): ``(kept, stats, record)``.

    ``kept``: the best robust grasps of each instance (:class:`_Kept`); ``stats``: per instance
    :class:`InstanceStats` (``sampled`` counts candidates, the others trials); ``record``: per instance the
    start's and the best score and the best variation.
    """
    search = config.search
    constraint = load_constraint(category)
    grasp_k = template.pose_names.index("grasp")
    stats = {name: InstanceStats() for name in instances}
    refs, pivots, searches, perts = [], [], [], []
    version = trial_code_version()
    for i, name in enumerate(instances):
        ref, pivot = warped_start(space, i, template, tip_H, config)
        refs.append(GraspMotion(ref, template.pose_names, dict(template.postures), "object", template.lift_height,
                                template.hold_time))
        pivots.append(pivot)
        seed = int(np.random.SeedSequence([config.seed, i]).generate_state(1)[0])
        searches.append(CemSearch(np.zeros(len(VARIATION_SCALE)), search.spread * VARIATION_SCALE,
                                  params=dataclasses.replace(search.cem, seed=seed)))
        perts.append([perturbation(search.robustness, name, k) for k in range(search.robustness.perturbations)])
    evaluated: list[list[tuple[float, GraspMotion]]] = [[] for _ in instances]  # candidates with a functional trial
    for rnd in range(search.cem.rounds):
        X = [sr.ask() for sr in searches]
        motions, specs, owners = {}, [], []
        for i, name in enumerate(instances):
            regions = annotations[name].get("regions", {})
            for j, v in enumerate(X[i]):
                m = vary_motion_about(refs[i], pivots[i], v)
                stats[name].sampled += 1
                if not constraint.check(m.poses[grasp_k], refs[i].poses[grasp_k], regions, tip_H)[0]:
                    stats[name].rejected_constraint += 1
                    continue
                motions[i, j] = m
                spec = ({"task": "robust_trial", "scenario": f"{category}_default", "category": category}
                        | _object_key(name, object_dirs) | {"motion": m.to_dict()})
                for p in perts[i]:
                    specs.append(spec | {"perturbation": p})
                    owners.append((i, j))
        outcomes = run_tasks(robust_trial_task, specs, cache_dir=config.cache_dir, code_version=version,
                             workers=config.workers, ray_address=config.ray,
                             progress=(lambda o, d, t: progress("trials", d, t)) if progress else None)
        trials: dict[tuple[int, int], list[dict]] = {}
        for key, out in zip(owners, outcomes):
            r = out.result
            _tally(stats[instances[key[0]]], error=r.get("status") == "error", reason=r.get("reason"),
                   sim_s=r.get("sim_s", 0), grasp=r.get("grasp"), functional=r.get("functional"))
            trials.setdefault(key, []).append(r)
        w = search.robustness.grasp_weight
        for i, sr in enumerate(searches):
            scores = np.zeros(len(X[i]))
            for j in range(len(X[i])):
                ts = trials.get((i, j), [])
                if ts:
                    scores[j] = float(np.mean([trial_score(t, w) for t in ts]))
                    if any(t.get("functional") for t in ts):
                        evaluated[i].append((scores[j], motions[i, j]))
            sr.tell(scores)
        if progress:
            progress("search", rnd + 1, search.cem.rounds)
    kept, record = [], {}
    for i, name in enumerate(instances):
        best = sorted(evaluated[i], key=lambda e: -e[0])[:search.keep]  # stable: the earlier of equal scores
        kept += [_Kept(i, m, float(score)) for score, m in best]
        res = searches[i].result
        record[name] = {"start_score": round(float(res.scores[0][0]), 4), "best_score": round(res.best_score, 4),
                        "best_variation": variation_dict(res.best), "kept": [round(float(b[0]), 4) for b in best]}
    return kept, stats, record


#: How ``--regressor auto`` chooses (``core.regression.select_regressor``): the simplest candidate within one
#: standard error of the least leave-one-instance-out error. Nested leave-one-instance-out on the committed
#: searched models (``benchmarks/bench_regression.py``), least-error rule -> one-SE rule: drill 5.6 -> 5.1 mm,
#: spray bottle 10.7 -> 9.8, mug 5.6 -> 5.6 (the least-error choice among 23 candidates on 10-13 instances
#: overfits).
REGRESSOR_RULE = "one_se"


def fit_grasp_regressor(X, Y, groups, weights, config: TrainingConfig, template: GraspMotion, anchor_H):
    """The regressor latent -> canonical descriptor: ``(regressor, selection)``.

    ``config.regressor == "ridge"``: ridge with ``config.ridge_alpha`` (rows weighted as in
    ``core.regression.fit_ridge``). ``"auto"``: on the instances' (weighted) mean descriptors, the
    candidate of ``core.regression.REGRESSOR_GRID`` chosen by leave-one-instance-out error of the
    functional point (m) with the one-standard-error rule (:data:`REGRESSOR_RULE`); ``selection`` names
    it, with each family's best error (mm). With fewer than 3 instances holding grasps there is nothing
    to choose with: ridge, and ``selection`` says why.
    """
    X, Y, groups = np.asarray(X, float), np.asarray(Y, float), np.asarray(groups)
    if config.regressor == "ridge":
        return fit_ridge(X, Y, alpha=config.ridge_alpha, groups=groups, weights=weights), {"regressor": "ridge"}
    _, x, y = instance_means(X, Y, groups, weights)
    if len(x) < 3:  # nothing to choose with: leave-one-instance-out needs 3
        return (fit_ridge(X, Y, alpha=config.ridge_alpha, groups=groups, weights=weights),
                {"regressor": "ridge", "note": f"only {len(x)} instances with grasps: no leave-one-out choice"})
    g = np.arange(len(x))

    def error(pred, rows):
        c = functional_point(pred, template, anchor_H)
        return float(np.mean([np.linalg.norm(c - functional_point(r, template, anchor_H)) for r in rows]))

    scored = score_regressors(x, y, g, error)  # every candidate once; each family's best and the choice from it
    families = {n: choose_regressor([c for c in scored if c[0] == n]) for n in REGRESSOR_GRID}
    name, hyper, err = choose_regressor(scored, REGRESSOR_RULE)
    regressor = REGRESSOR_GRID[name][0](x, y, g, **hyper)
    return regressor, {"regressor": name, "hyperparameters": hyper, "loo_error_mm": round(1000 * err, 2),
                       "rule": REGRESSOR_RULE,
                       "loo_error_mm_by_family": {n: round(1000 * f[2], 2) for n, f in families.items()},
                       "hyperparameters_by_family": {n: f[1] for n, f in families.items()}}


#: The candidates of :func:`choose_regressor_by_trials`, simplest first (its one-standard-error rule keeps the
#: first within one standard error of the best): the category's canonical grasp itself (no learning), then
#: the families of ``core.regression.REGRESSOR_GRID`` in ``core.regression.SIMPLICITY`` order.
TRIAL_CANDIDATES = ("canonical", *SIMPLICITY)


def canonical_regressor(template: GraspMotion, q: int) -> LinearRegressor:
    """The regressor that ignores shape and returns the canonical grasp ``template`` (canonical frame)."""
    d = descriptor_vector(template)
    return LinearRegressor(coef=np.zeros((len(d), q)), intercept=d, alpha=0.0)


def choose_regressor_by_trials(category, space, instances, template, tip_H, X, Y, groups, weights, hyperparameters,
                               robustness: Robustness, config: TrainingConfig, *, object_dirs=(), progress=None):
    """The latent -> grasp regressor chosen by grasp trials: ``(regressor, record)``.

    Every candidate of :data:`TRIAL_CANDIDATES` (the families with ``hyperparameters``: name -> dict, e.g. each
    family's best by leave-one-instance-out error) is trained on all training instances but one and its grasp
    for the left-out instance -- R(x_i) warped by W(x_i), what the transfer executes under perfect perception
    -- is scored there by ``robustness`` trials (the search's: nominal placement and seeded perturbations).
    The candidate kept is the simplest whose mean score is within one standard error of the best (the
    best's per-instance scores); it is then fitted on every instance. ``"canonical"`` needs no fit and is
    scored the same way. ``record``: each candidate's per-instance scores and the choice.

    Why: the regressor's error at the functional point measures the distance to the left-out instance's
    kept grasp, not whether the prediction grasps it; averaging robust per-instance grasps can land off
    each instance's robust region (the session-12 mug model's mean grasp missed 3 of its 13 training mugs
    that the canonical grasp holds).
    """
    labels, x, y = instance_means(X, Y, groups, weights)
    labels = [int(v) for v in labels]
    q = space.latent_train.shape[1]
    canonical = descriptor_vector(template)
    fitted = {}  # (candidate, left-out instance) -> predicted descriptor
    for i in range(len(instances)):
        others = [k for k, lab in enumerate(labels) if lab != i]
        xi = space.latent_train[i]
        fitted["canonical", i] = canonical
        for name in SIMPLICITY:
            fit = REGRESSOR_GRID[name][0]
            fitted[name, i] = fit(x[others], y[others], np.arange(len(others)), **hyperparameters[name]).predict(xi)
    specs, owners = [], []
    for (name, i), d in fitted.items():
        canon = motion_from_descriptor(d, template)
        poses = warp_poses(space.canonical, space.decode(space.latent_train[i]), space.beta, canon.poses,
                           anchor=tip_H, rotation_radius=config.grasp_rotation_radius)
        m = GraspMotion(poses, template.pose_names, dict(canon.postures), "object", template.lift_height,
                        template.hold_time)
        spec = ({"task": "robust_trial", "scenario": f"{category}_default", "category": category}
                | _object_key(instances[i], dict(object_dirs)) | {"motion": m.to_dict()})
        for k in range(robustness.perturbations):
            specs.append(spec | {"perturbation": perturbation(robustness, instances[i], k)})
            owners.append((name, i))
    outcomes = run_tasks(robust_trial_task, specs, cache_dir=config.cache_dir, code_version=trial_code_version(),
                         workers=config.workers, ray_address=config.ray,
                         progress=(lambda o, d, t: progress("trials", d, t)) if progress else None)
    trials: dict[tuple[str, int], list[float]] = {}
    for key, out in zip(owners, outcomes):
        trials.setdefault(key, []).append(trial_score(out.result, robustness.grasp_weight))
    scores = {name: np.array([np.mean(trials[name, i]) for i in range(len(instances))]) for name in TRIAL_CANDIDATES}
    name = simplest_within_one_se(scores, TRIAL_CANDIDATES)
    if name == "canonical":
        regressor, hyper = canonical_regressor(template, q), {}
    else:
        hyper = hyperparameters[name]
        regressor = REGRESSOR_GRID[name][0](x, y, np.arange(len(x)), **hyper)
    record = {"regressor": name, "hyperparameters": hyper, "rule": "one_se",
              "trial_score": round(float(np.mean(scores[name])), 4),
              "trial_scores": {n: [round(float(v), 4) for v in scores[n]] for n in TRIAL_CANDIDATES},
              "trial_score_by_candidate": {n: round(float(np.mean(scores[n])), 4) for n in TRIAL_CANDIDATES},
              "trials": len(specs), "instances": list(instances)}
    return regressor, record


def _sampled_training_grasps(category, space, instances, template, config, annotations, tip_H, progress,
                             object_dirs=()):
    """The paper's step 3: random samples around the warped motion, each one trial; its functional successes."""
    candidates, stats = sample_training_motions(category, space, instances, template, config, annotations, tip_H)
    specs = [{"task": "grasp_trial", "scenario": f"{category}_default", "category": category}
             | _object_key(instances[c.instance_index], object_dirs) | {"motion": c.motion.to_dict()}
             for c in candidates]
    outcomes = run_tasks(grasp_trial_task, specs, cache_dir=config.cache_dir, code_version=trial_code_version(),
                         workers=config.workers, ray_address=config.ray,
                         progress=(lambda o, d, t: progress("trials", d, t)) if progress else None)
    kept = []
    for cand, out in zip(candidates, outcomes):
        r = out.result
        simulated = _tally(stats[instances[cand.instance_index]], error=r.get("status") == "error",
                           reason=r.get("failure_reason"), sim_s=r.get("sim_time_s", 0),
                           grasp=r.get("grasp_success"), functional=r.get("functional_success"))
        if simulated and r.get("functional_success"):
            kept.append(_Kept(cand.instance_index, cand.motion, 1.0))
    return kept, stats


def _choose_regressor(category, space, instances, template, tip_H, X, Y, groups, weights, config, robustness,
                      object_dirs, progress):
    """:func:`fit_grasp_regressor`, then, with ``config.regressor == "trials"``,
    :func:`choose_regressor_by_trials` among its families: ``(regressor, stats["regression"])``."""
    regressor, selection = fit_grasp_regressor(X, Y, groups, weights, config, template, tip_H)
    if config.regressor != "trials" or "hyperparameters_by_family" not in selection:
        return regressor, selection
    regressor, by_trials = choose_regressor_by_trials(
        category, space, instances, template, tip_H, X, Y, groups, weights, selection["hyperparameters_by_family"],
        robustness, config, object_dirs=object_dirs, progress=progress)
    return regressor, by_trials | {"chosen_by": "trials", "by_loo_error": selection}


def refit_regressor(model: CategoryModel, config: TrainingConfig = TrainingConfig(regressor="auto"),
                    progress=None) -> CategoryModel:
    """``model`` with its regressor chosen and fitted again on its own stored training set, as
    ``train_category`` would with ``config`` (e.g. after a change of :data:`REGRESSOR_RULE`); no grasp
    search. ``config.regressor == "trials"`` runs the choice's grasp trials (with the robustness
    perturbations the model was searched with). ``stats["regression"]`` is replaced and says so."""
    if model.training_latent is None:
        raise InputError("refit_regressor: the model file holds no training set")
    searched = (model.params.get("search") or {}).get("robustness")
    robustness = Robustness(**{k: tuple(v) if isinstance(v, list) else v for k, v in searched.items()}) \
        if searched else Robustness()
    regressor, selection = _choose_regressor(
        model.category, model.space, list(model.instances), model.template, np.asarray(model.grasp_anchor_H),
        model.training_latent, model.training_descriptors, model.training_groups, model.training_weights, config,
        robustness, model.params.get("objects", {}), progress)
    stats = dict(model.stats) | {"regression": selection | {"refitted": True}}
    params = dict(model.params) | {"regressor": config.regressor}
    return dataclasses.replace(model, regressor=regressor, stats=stats, params=params)


def _region_centre(annotations: dict, region: str, name: str) -> np.ndarray:
    regions = annotations.get("regions", {})
    if region not in regions:
        raise InputError(f"{name}: no {region!r} region annotated; choosing the canonical instance by "
                         "region needs it on every training instance")
    return np.asarray(regions[region]["center"], float)


def choose_canonical_by_region(clouds, region_centres, shape_kwargs: dict, progress=None):
    """The canonical instance that carries the functional region best: for each candidate k, the shape
    space with k as canonical; k's annotated region centre warped by each instance's CPD field
    (``deform_points``) against that instance's own centre (object frame, m). Returns (index of the
    lowest mean error, the mean error of every candidate (m), the chosen candidate's space).

    A grasp is anchored at the region, so this is the error with which the canonical grasp starts on every
    training instance (session-16 spray bottles: the first, flat one as canonical 8.1 mm mean, up to 22.5 mm
    on the deep ones; the deep ones 2.4-4.1 mm; training.md). It costs one shape space per instance
    (K * (K - 1) registrations).
    """
    centres = np.asarray(region_centres, float)
    K = len(clouds)
    errors, best = np.zeros(K), None
    for k in range(K):
        space = build_shape_space(clouds, canonical_index=k, **shape_kwargs)
        warped = np.array([deform_points(space.canonical, space.W_train[i], space.beta, centres[k:k + 1])[0]
                           for i in range(K)])
        errors[k] = np.mean(np.linalg.norm(warped - centres, axis=1)[np.arange(K) != k])
        if best is None or errors[k] < errors[best[0]]:
            best = (k, space)
        if progress is not None:
            progress(k + 1, K)
    return best[0], errors, best[1]


def train_category(
    category: str,
    instances: list[str] | None = None,
    config: TrainingConfig = TrainingConfig(),
    *,
    objects=(),
    progress: Callable[[str, int, int], None] | None = None,
) -> CategoryModel:
    """Algorithm 1 on ``instances`` of ``category`` (default: all embedded ones) and ``objects``.

    ``objects``: directories of imported objects (``catgrasp import-object``) of the same category,
    trained on like embedded instances, after them (their annotated functional region is what the
    constraint and the judge use). ``progress(stage, done, total)`` reports "shape" (CPD
    registrations) and "trials" progress. Raises InputError when no instance gets a functional
    success (nothing to learn from).
    """
    t0 = time.perf_counter()
    instances = list(instances) if instances is not None else list_instances(category)
    object_dirs = {}
    for directory in objects:
        obj_category, name = imported_object(directory)
        if obj_category != category:
            raise InputError(f"{directory}: is a {obj_category} object, not {category}")
        if name in instances or name in object_dirs:
            raise InputError(f"{directory}: an instance named {name!r} is already in the training set")
        object_dirs[name] = str(directory)
    instances += list(object_dirs)
    if len(instances) < 2:
        raise InputError(f"training needs at least 2 instances, got {len(instances)}")
    canonical = config.canonical_instance or instances[0]
    if canonical not in instances and canonical != "region":
        raise InputError(f"canonical instance {canonical!r} is not among the training instances")

    clouds = [full_cloud(read_mesh(Path(object_dirs[n]) / f"{n}.obj"), voxel=config.cloud_voxel) if n in object_dirs
              else instance_clouds(category, [n], config.cloud_voxel)[0] for n in instances]
    annotations = {n: read_annotations(Path(object_dirs[n]) / "annotations.json") if n in object_dirs
                   else load_annotations(category, n) for n in instances}
    canonical_choice = None
    if canonical == "region":
        region = load_constraint(category).region
        c_index, errors, space = choose_canonical_by_region(
            clouds, [_region_centre(annotations[n], region, n) for n in instances], config.shape_kwargs(),
            progress=(lambda d, t: progress("canonical", d, t)) if progress else None)
        canonical = instances[c_index]
        canonical_choice = {"by": f"mean {region} warp error (mm)",
                            "errors_mm": {n: round(1000 * e, 2) for n, e in zip(instances, errors)}}
    else:
        space = build_shape_space(clouds, canonical_index=instances.index(canonical), progress=(
            (lambda d, t: progress("shape", d, t)) if progress else None), **config.shape_kwargs())
    t_shape = time.perf_counter() - t0

    template = load_handwritten_motion(category, canonical, config.grasp_file,
                                       annotations_dir=object_dirs.get(canonical))
    tip_H = functional_point_in_hand(template, annotations[canonical], load_constraint(category).region)
    t1 = time.perf_counter()
    if config.search is None:
        kept, stats = _sampled_training_grasps(category, space, instances, template, config, annotations, tip_H,
                                               progress, object_dirs)
        search_record = None
    else:
        kept, stats, search_record = search_training_grasps(category, space, instances, template, config,
                                                            annotations, tip_H, progress, object_dirs)
    t_trials = time.perf_counter() - t1
    if not kept:
        raise InputError(f"{category}: no sampled grasp succeeded functionally on any training instance; "
                         "nothing to learn (check the canonical grasp with diagrams/execute_grasp.py)")
    X, Y, groups, weights = [], [], [], []
    for k in kept:
        canon = inverse_warp_poses(space.canonical, space.W_train[k.instance_index], space.beta, k.motion.poses,
                                   anchor=tip_H, rotation_radius=config.grasp_rotation_radius)
        m = GraspMotion(canon, template.pose_names, dict(k.motion.postures), "object", template.lift_height,
                        template.hold_time)
        X.append(space.latent_train[k.instance_index])
        Y.append(descriptor_vector(m))
        groups.append(k.instance_index)
        weights.append(k.weight)
    weights = None if config.search is None else np.array(weights)
    regressor, selection = _choose_regressor(category, space, instances, template, tip_H, X, Y, groups, weights,
                                             config, (config.search or InstanceSearch()).robustness, object_dirs,
                                             progress)
    n_sim = sum(s.simulated for s in stats.values())
    summary = {
        "trials_simulated": n_sim,
        "trials_functional": sum(s.functional for s in stats.values()),
        "trials_grasped": sum(s.grasped for s in stats.values()),
        "instances_with_functional_success": sum(1 for s in stats.values() if s.functional > 0),
        "instances": len(instances),
        "shape_time_s": round(t_shape, 2),
        "trial_time_s": round(t_trials, 2),
        "total_time_s": round(time.perf_counter() - t0, 2),
        "trials_per_s": round(n_sim / t_trials, 3) if t_trials > 0 else None,
        "per_instance": {n: asdict(s) for n, s in stats.items()},
        "q": space.q,
        "regression": selection,
    }
    if search_record is not None:
        summary["search"] = search_record
    if canonical_choice is not None:
        summary["canonical_choice"] = canonical_choice
    params = {k: (asdict(v) if hasattr(v, "__dataclass_fields__") else v) for k, v in asdict(config).items()}
    for run_only in ("cache_dir", "workers", "ray"):
        params.pop(run_only, None)
    if object_dirs:
        params["objects"] = object_dirs
    return CategoryModel(category=category, space=space, regressor=regressor, template=template,
                         instances=tuple(instances), canonical_instance=canonical, params=params, stats=summary,
                         grasp_anchor_H=tuple(float(v) for v in tip_H),
                         grasp_rotation_radius=config.grasp_rotation_radius,
                         training_latent=np.array(X), training_descriptors=np.array(Y),
                         training_groups=np.array(groups, np.int64), training_weights=weights)


def train_category_folder(folder, config: TrainingConfig = TrainingConfig(), *, objects_out=None,
                          progress: Callable[[str, int, int], None] | None = None):
    """A new category from a folder of meshes (``data.category_folder``): every mesh imported into
    ``objects_out`` (default ``out/categories/<name>``), then Algorithm 1 on those objects alone, with the
    folder's canonical instance and hand-written grasp. Returns ``(model, imported objects)``; the model is
    of the like-category (its judge, constraint and postures) and ``params["family"]`` names the new one."""
    cat = read_category_folder(folder)
    imported = import_category(cat.folder, out=objects_out)
    config = dataclasses.replace(config, canonical_instance=imported[0].name, grasp_file=str(cat.grasp))
    model = train_category(cat.like, [], config, objects=[o.directory for o in imported], progress=progress)
    family = {"name": cat.name, "like": cat.like, "folder": str(cat.folder), "description": cat.description}
    return dataclasses.replace(model, params=dict(model.params) | {"family": family}), imported
