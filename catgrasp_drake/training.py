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
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.core.deformation import inverse_warp_poses, warp_poses
from catgrasp_drake.core.regression import fit_ridge
from catgrasp_drake.core.shape_space import build_shape_space
from catgrasp_drake.data.dataset import instance_clouds, list_instances, load_annotations
from catgrasp_drake.errors import InputError
from catgrasp_drake.grasping.constraints import load_constraint
from catgrasp_drake.grasping.descriptor import descriptor_vector
from catgrasp_drake.grasping.motion import GraspMotion
from catgrasp_drake.grasping.sampling import SamplingParams, perturb_poses, perturbations
from catgrasp_drake.runner import code_fingerprint, run_tasks
from catgrasp_drake.station.handwritten import load_handwritten_motion
from catgrasp_drake.station.scenario import load_scenario
from catgrasp_drake.trial import run_grasp_trial

_ROOT = Path(__file__).resolve().parents[1]
#: Files whose contents decide a trial's outcome: the trial cache is keyed by their hash.
TRIAL_CODE_PATHS = (
    _ROOT / "catgrasp_drake" / "station",
    _ROOT / "catgrasp_drake" / "planning",
    _ROOT / "catgrasp_drake" / "systems" / "grasp_execution.py",
    _ROOT / "catgrasp_drake" / "trial.py",
    _ROOT / "catgrasp_drake" / "robot",
    _ROOT / "catgrasp_drake" / "grasping" / "motion.py",
    _ROOT / "models" / "svh",
    _ROOT / "models" / "ur10",
    _ROOT / "models" / "station.scenarios.yaml",
    _ROOT / "models" / "objects",
)


@dataclass(frozen=True)
class TrainingConfig:
    """Parameters of :func:`train_category` (SI units)."""

    samples_per_instance: int = 12
    sampling: SamplingParams = SamplingParams()
    seed: int = 0
    canonical_instance: str | None = None  # None: the first instance
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
    workers: int | None = None  # None: all cores
    cache_dir: str | None = "out/trial_cache"
    ray: str | None = None  # Ray address ("auto", "local", "host:port") or None: local worker processes

    def shape_kwargs(self) -> dict:
        kw = {"variance": self.variance}
        if self.beta is not None:
            kw["beta"] = self.beta
        if self.lam is not None:
            kw["lam"] = self.lam
        return kw


def grasp_trial_task(spec: dict) -> dict:
    """Worker task: one grasp trial of ``spec["motion"]`` (object frame) on one instance."""
    base = load_scenario(spec["scenario"])
    scenario = base.replace(name=f"{spec['scenario']}:{spec['instance']}",
                            object=dataclasses.replace(base.object, category=spec["category"],
                                                       instance=spec["instance"]))
    result = run_grasp_trial(scenario, GraspMotion.from_dict(spec["motion"]))
    return result.to_dict()


def trial_code_version() -> str:
    return code_fingerprint(TRIAL_CODE_PATHS)


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


def sample_training_motions(category, space, instances, template, config, annotations, tip_H):
    """Warped + perturbed motions per instance, filtered by the functional constraint."""
    constraint = load_constraint(category)
    stats = {name: InstanceStats() for name in instances}
    candidates: list[_Candidate] = []
    grasp_k = template.pose_names.index("grasp")
    for i, name in enumerate(instances):
        ref = warp_poses(space.canonical, space.W_train[i], space.beta, template.poses, anchor=tip_H,
                         rotation_radius=config.grasp_rotation_radius)
        centre = ref[grasp_k, :3, :3] @ tip_H + ref[grasp_k, :3, 3]  # perturb about the grasp centre
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


def train_category(
    category: str,
    instances: list[str] | None = None,
    config: TrainingConfig = TrainingConfig(),
    *,
    progress: Callable[[str, int, int], None] | None = None,
) -> CategoryModel:
    """Algorithm 1 on ``instances`` of ``category`` (default: all embedded ones).

    ``progress(stage, done, total)`` reports "shape" (CPD registrations) and
    "trials" progress. Raises InputError when no instance gets a functional
    success (nothing to learn from).
    """
    t0 = time.perf_counter()
    instances = list(instances) if instances is not None else list_instances(category)
    if len(instances) < 2:
        raise InputError(f"training needs at least 2 instances, got {len(instances)}")
    canonical = config.canonical_instance or instances[0]
    if canonical not in instances:
        raise InputError(f"canonical instance {canonical!r} is not among the training instances")
    c_index = instances.index(canonical)

    clouds = instance_clouds(category, instances, config.cloud_voxel)
    space = build_shape_space(clouds, canonical_index=c_index, progress=(
        (lambda d, t: progress("shape", d, t)) if progress else None), **config.shape_kwargs())
    t_shape = time.perf_counter() - t0

    template = load_handwritten_motion(category, canonical)
    annotations = {n: load_annotations(category, n) for n in instances}
    tip_H = functional_point_in_hand(template, annotations[canonical], load_constraint(category).region)
    candidates, stats = sample_training_motions(category, space, instances, template, config, annotations, tip_H)
    specs = [{"task": "grasp_trial", "scenario": f"{category}_default", "category": category,
              "instance": instances[c.instance_index], "motion": c.motion.to_dict()} for c in candidates]
    t1 = time.perf_counter()
    outcomes = run_tasks(grasp_trial_task, specs, cache_dir=config.cache_dir, code_version=trial_code_version(),
                         workers=config.workers, ray_address=config.ray,
                         progress=(lambda o, d, t: progress("trials", d, t)) if progress else None)
    t_trials = time.perf_counter() - t1

    X, Y, groups = [], [], []
    for cand, out in zip(candidates, outcomes):
        name = instances[cand.instance_index]
        st = stats[name]
        r = out.result
        if r.get("status") == "error":
            st.errors += 1
            continue
        if r.get("failure_reason") in ("unreachable", "collision_before_closing") and r.get("sim_time_s", 0) == 0:
            st.rejected_plan += 1
            continue
        st.simulated += 1
        st.grasped += bool(r.get("grasp_success"))
        if r.get("functional_success"):
            st.functional += 1
            i = cand.instance_index
            canon = inverse_warp_poses(space.canonical, space.W_train[i], space.beta, cand.motion.poses,
                                       anchor=tip_H, rotation_radius=config.grasp_rotation_radius)
            m = GraspMotion(canon, template.pose_names, dict(template.postures), "object",
                            template.lift_height, template.hold_time)
            X.append(space.latent_train[i])
            Y.append(descriptor_vector(m))
            groups.append(i)
    if not Y:
        raise InputError(f"{category}: no sampled grasp succeeded functionally on any training instance; "
                         "nothing to learn (check the canonical grasp with diagrams/execute_grasp.py)")
    regressor = fit_ridge(np.array(X), np.array(Y), alpha=config.ridge_alpha, groups=groups)
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
    }
    params = {k: (asdict(v) if hasattr(v, "__dataclass_fields__") else v) for k, v in asdict(config).items()}
    for run_only in ("cache_dir", "workers", "ray"):
        params.pop(run_only, None)
    return CategoryModel(category=category, space=space, regressor=regressor, template=template,
                         instances=tuple(instances), canonical_instance=canonical, params=params, stats=summary,
                         grasp_anchor_H=tuple(float(v) for v in tip_H),
                         grasp_rotation_radius=config.grasp_rotation_radius,
                         training_latent=np.array(X), training_descriptors=np.array(Y),
                         training_groups=np.array(groups, np.int64))
