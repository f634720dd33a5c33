"""What each grasp-prediction method makes of one shape estimate (pure functions, numpy/scipy).

Every method starts from the same kind of estimate -- a latent vector x, the
rigid pose X_WO of the canonical frame O in the world W, a uniform scale s,
the observed cloud and the completed shape (both in W) -- and returns a
grasping motion in W. They differ in the estimator they are paired with
(:data:`ESTIMATORS`) and in what they predict:

``latent``       this project's method: latent shape + similarity fit with the
                 visibility-aware E-step, regressed grasp R(x) warped by W(x).
``paper``        the paper's plain latent fit (no visibility model: every model
                 point is a mixture centre, as in eq. 15), then the same R(x), W(x).
``rigid``        the canonical motion on the canonical shape aligned by a
                 similarity only (the shape space's deformation switched off).
``cpd``          the rigid alignment, then direct non-rigid CPD from the aligned
                 canonical shape to the observation; the canonical grasp pose is
                 warped by that field and the other control poses keep their
                 offsets from it (no latent space; see :func:`predict_motion`).
``nearest``      the latent fit, then the mean grasp of the training instance
                 whose latent vector is closest, warped by W(x) (no regression).
``latent_map``   ``latent`` with one shape hypothesis (the yaw search's best start
                 only; the project's method before the shape posterior): an ablation
                 row that measures what the posterior choice changes.
``latent_fast``  ``latent_map`` with a shorter fit (:data:`FAST_ESTIMATE`: the yaw search's
                 starts 8 EM iterations instead of 12, the refine at most 12 instead of 40):
                 perception to motion in ~50 ms instead of ~160 (issue 17;
                 ``benchmarks/bench_transfer.py --settings new fast``), an ablation row that
                 measures what the speed costs in success.
``true_object``  ``latent``'s grasp, planned around the TRUE object instead of the
                 perceived shape: an ablation row, not a method a robot can run.
``latent_plain`` ``latent`` with its shape hypotheses weighted by their plain energy (eq. 15 with
                 every model point a mixture centre, ``core.inference.plain_energy``) instead of
                 the visibility-aware fit's: an ablation row (session 45). On validation drills it
                 never ranks a drill turned round first (today's weights: 4 of 144 views); on a
                 large real drill it prefers the turned fit, so it is not the default
                 (``benchmarks/results/experiments/s45_yaw_rank``).

Shape posterior (``latent``): the estimator refines the ``hypotheses`` best
starts of its yaw search (:func:`catgrasp_drake.core.inference.infer_latent_pose`)
and keeps the distinct fits. :func:`grasp_candidates` predicts a grasp for each,
weights each hypothesis by its tempered likelihood ``exp(-(E - E_min) / T)``
(:data:`POSTERIOR_TEMPERATURE`; on drills E pays :data:`UNCOVERED_NATS` per observed
point the hypothesis' completed shape leaves uncovered, :func:`ranking_energies`:
a drill fitted turned round leaves its handle's points unexplained), and ranks the grasps by their *support*: the
posterior mass of the hypotheses on which the grasp's functional point lands
within :data:`SUPPORT_RADIUS_M` of theirs. The planner executes the first
candidate it can plan without collision (``MotionPlanner``'s
``grasp_candidates_W``), so a grasp refused on the most likely shape falls back
to the next plausible one instead of no motion.

Pose warping uses the model's functional-point anchor and rotation radius
throughout. Frames: W world, O canonical object frame; metres.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from catgrasp_drake.category_model import CategoryModel, apply_similarity_to_poses
from catgrasp_drake.core.cpd import nonrigid_cpd
from catgrasp_drake.core.deformation import warp_poses
from catgrasp_drake.core.threads import single_threaded_blas
from catgrasp_drake.errors import InputError
from catgrasp_drake.grasping.descriptor import motion_from_descriptor, motion_functional_point
from catgrasp_drake.grasping.motion import GraspMotion

METHODS = ("latent", "paper", "rigid", "cpd", "nearest", "true_object", "latent_map", "latent_fast",
           "latent_plain")
#: The methods whose grasp is the regressor's R(x) warped by W(x) (they differ only in their estimate).
REGRESSED_METHODS = ("latent", "paper", "true_object", "latent_map", "latent_fast", "latent_plain")


@dataclasses.dataclass(frozen=True)
class EstimatorSetup:
    """How a method's shape estimate is made: a rigid (deformation-free) space, the visibility model, the
    shape hypotheses kept and other ``infer_latent_pose`` options (``inference``: (name, value) pairs)."""

    rigid: bool = False
    visibility: bool = True
    #: Shape hypotheses the estimator keeps (``infer_latent_pose(hypotheses=...)``); 1: the MAP fit only.
    hypotheses: int = 1
    inference: tuple = ()

    @property
    def inference_kwargs(self) -> dict:
        """The estimator's keyword arguments: ``inference`` and, above one, ``hypotheses``."""
        return dict(self.inference) | ({"hypotheses": self.hypotheses} if self.hypotheses > 1 else {})


#: Shape hypotheses of the latent method. On the committed instances (3 seeded placements each; out-of-split
#: tuning, ``benchmarks/bench_posterior.py``), views with the yaw within 10 deg for 1/2/3/4 hypotheses: mugs
#: 24/24/26/26 of 45, drills 39 of 39 throughout, spray bottles 44/47/47/48 of 51; each more costs one refine.
POSTERIOR_HYPOTHESES = 3
#: Temperature (nats) of the hypotheses' weights ``exp(-(E - E_min) / T)``: the mean log-probability of the
#: right mug hypotheses (yaw within 10 deg) on the same views is -3.34 at 1, -0.88 at 5, -0.47 at 15,
#: -0.78 at 40; the EM energy's raw likelihood (T = 1) is far too sure.
POSTERIOR_TEMPERATURE = 15.0
#: A grasp is well placed on a hypothesis when its functional point is within this of that
#: hypothesis' grasp's functional point (m): about the trigger's and handle's half-width.
SUPPORT_RADIUS_M = 0.01
#: Methods whose shape hypotheses are weighted by their plain energy (every model point a mixture centre;
#: ``core.inference.plain_energy``) instead of the visibility-aware fit's energy.
PLAIN_RANKED_METHODS = ("latent_plain",)
#: Nats added to a hypothesis' energy per observed point its completed shape leaves uncovered
#: (``ShapeHypothesis.uncovered``), when :func:`ranking_energies` ranks for these categories: about what an
#: outlier costs against a well-explained point at a fitted drill's or mug's sigma^2. Adopted per category by the
#: rule of ``benchmarks/results/experiments/s47_coverage`` (validation views, then simulated validation trials).
UNCOVERED_NATS = 5.0
COVERAGE_RANKED_CATEGORIES = ("drill",)
#: Categories whose shape hypotheses are refined once more from the best fit's shape
#: (``infer_latent_pose(reseed=True)``) by the methods that keep several (:func:`estimator_kwargs`). Adopted per
#: category by the rule of ``benchmarks/results/experiments/s48_reseed`` (validation views, then simulated
#: validation trials); it costs up to two more refines per view.
RESEEDED_CATEGORIES = ("mug",)


#: The shorter latent fit of ``latent_fast`` (``infer_latent_pose`` options): chosen on the committed held-out
#: instances by ``benchmarks/bench_transfer.py`` (session 23); 6 search iterations lost the yaw there.
FAST_ESTIMATE = {"search_iter": 8, "max_iter": 12}

#: The estimator each method is paired with.
ESTIMATORS = {
    "latent": EstimatorSetup(hypotheses=POSTERIOR_HYPOTHESES),
    "paper": EstimatorSetup(visibility=False),
    "rigid": EstimatorSetup(rigid=True),
    "cpd": EstimatorSetup(rigid=True),
    "nearest": EstimatorSetup(),
    "true_object": EstimatorSetup(hypotheses=POSTERIOR_HYPOTHESES),
    "latent_map": EstimatorSetup(),
    "latent_fast": EstimatorSetup(inference=tuple(FAST_ESTIMATE.items())),
    "latent_plain": EstimatorSetup(hypotheses=POSTERIOR_HYPOTHESES, inference=(("plain_energies", True),)),
}

#: Direct CPD's settings (outlier weight, iterations, tolerance).
CPD_OPTIONS = {"w": 0.05, "max_iter": 100, "tol": 1e-5}


def estimator_kwargs(method: str, category: str | None = None) -> dict:
    """The ``infer_latent_pose`` options of ``method``'s estimator for an object of ``category``: its
    :data:`ESTIMATORS` set-up, with ``reseed`` for the categories in :data:`RESEEDED_CATEGORIES` when the method
    keeps several shape hypotheses."""
    setup = ESTIMATORS[check_method(method)]
    kwargs = setup.inference_kwargs
    if setup.hypotheses > 1 and category in RESEEDED_CATEGORIES:
        kwargs["reseed"] = True
    return kwargs


def check_method(method: str) -> str:
    if method not in METHODS:
        raise InputError(f"unknown method {method!r}; known: {', '.join(METHODS)}")
    return method


def rigid_space(space):
    """The shape space with its deformation switched off: every latent vector decodes to the canonical shape."""
    return dataclasses.replace(space, W_mean=np.zeros_like(space.W_mean),
                               components=np.zeros_like(space.components))


def nearest_instance(model: CategoryModel, x) -> int:
    """Index of the training instance with at least one stored success whose latent vector is closest to x."""
    if model.training_groups is None:
        raise InputError("the nearest-instance baseline needs a model file with its training set")
    with_success = np.unique(model.training_groups)
    d = np.linalg.norm(model.space.latent_train[with_success] - np.asarray(x, float), axis=1)
    return int(with_success[int(np.argmin(d))])


def _placed(model: CategoryModel, poses_O: np.ndarray, X_WO: np.ndarray, s: float) -> np.ndarray:
    return apply_similarity_to_poses(poses_O, X_WO[:3, :3], X_WO[:3, 3], s, anchor=model.grasp_anchor_H)


def _motion(poses_W: np.ndarray, like: GraspMotion) -> GraspMotion:
    return GraspMotion(poses_W, like.pose_names, dict(like.postures), "world", like.lift_height, like.hold_time)


def predict_motion(method: str, model: CategoryModel, x, X_WO, scale: float, *, observed_W=None,
                   completed_W=None) -> tuple[GraspMotion, str]:
    """``method``'s grasping motion in W for an estimate (module docstring), and a one-line note.

    ``x`` (q,), ``X_WO`` 4x4 rigid, ``scale`` > 0. ``cpd`` also needs the
    observed cloud and the estimator's completed (here: similarity-aligned
    canonical) shape, ``observed_W`` (N, 3) and ``completed_W`` (M, 3).
    Runs with BLAS single-threaded: in the transfer diagram OpenBLAS's threads,
    competing with the renderer's, made the warp's 786 x 786 kernel products
    2-3x slower (21-30 ms -> 9 ms per latent prediction, measured).
    """
    with single_threaded_blas():
        return _predict_motion(method, model, x, X_WO, scale, observed_W, completed_W)


def _predict_motion(method, model, x, X_WO, scale, observed_W, completed_W):
    check_method(method)
    X_WO = np.asarray(X_WO, float)
    s = float(scale)
    template = model.template
    if method in REGRESSED_METHODS:
        return model.transfer(x, X_WO[:3, :3], X_WO[:3, 3], s, frame="world"), ""
    if method == "rigid":
        return _motion(_placed(model, template.poses, X_WO, s), template), ""
    if method == "cpd":
        if observed_W is None or completed_W is None or len(observed_W) == 0 or len(completed_W) == 0:
            raise InputError("the cpd method needs the observed cloud and the aligned canonical shape")
        source = np.asarray(completed_W, float)
        beta = model.space.beta * s
        r = nonrigid_cpd(source, np.asarray(observed_W, float), beta=beta, lam=model.space.lam, **CPD_OPTIONS)
        placed = _placed(model, template.poses, X_WO, s)
        # Only the grasp pose is warped by the field. A CPD field fitted to one observation is meaningful
        # near the data only: with the shape space's wide kernel its coefficients cancel on the surface
        # but not 5 cm away, where it moved the pregrasp by 13-17 cm (measured on held-out drills,
        # full view) -- the cause of the baseline's 0/24 drills. The other control poses keep their
        # canonical offsets from the warped grasp.
        k = template.pose_names.index("grasp")
        G = warp_poses(source, r.W, beta, placed[k], **model.warp_options())
        poses = np.array([G @ np.linalg.solve(placed[k], X) for X in placed])
        poses[k] = G
        return _motion(poses, template), f"cpd: {r.iterations} iterations"
    k = nearest_instance(model, x)  # nearest
    canonical = motion_from_descriptor(model.instance_descriptor(k), template)
    warped = warp_poses(model.space.canonical, model.space.decode(x), model.space.beta, canonical.poses,
                        **model.warp_options())
    return _motion(_placed(model, warped, X_WO, s), canonical), f"nearest training instance: {model.instances[k]}"


# ----------------------------------------------------------------------------- the shape posterior
@dataclasses.dataclass(frozen=True, eq=False)
class ShapeHypothesis:
    """One fit of the shape posterior, in W: latent ``x`` (q,), pose ``X_WO`` 4x4, ``scale``, the completed
    shape ``completed_W`` (M, 3) m, its fit ``energy`` (nats, the visibility-aware fit's) and ``plain_energy``
    (nats: the same fit with every model point a mixture centre, ``core.inference.plain_energy``; NaN: not
    known) and ``uncovered``: the observed points farther than ``core.inference.UNCOVERED_RADIUS_M`` from every
    point of ``completed_W`` (``systems.shape_estimator.ShapeEstimate.uncovered``)."""

    x: np.ndarray
    X_WO: np.ndarray
    scale: float
    completed_W: np.ndarray
    energy: float
    plain_energy: float = float("nan")
    uncovered: int = 0


@dataclasses.dataclass(frozen=True, eq=False)
class GraspCandidate:
    """A grasp predicted for one shape hypothesis, with what the posterior says of it.

    ``motion`` in W; ``object_points_W`` (M, 3) the completed shape it was
    predicted for (the planner's obstacle for it); ``hypothesis`` its index
    in energy order (0 = the MAP fit); ``weight`` that hypothesis' posterior
    weight; ``support`` the posterior mass of the hypotheses on which its
    functional point is within :data:`SUPPORT_RADIUS_M` of theirs (its own
    included); ``functional_point_W`` (3,) m.
    """

    motion: GraspMotion
    object_points_W: np.ndarray
    hypothesis: int
    weight: float
    support: float
    functional_point_W: np.ndarray


def hypothesis_weights(energies, temperature: float = POSTERIOR_TEMPERATURE) -> np.ndarray:
    """Normalised weights ``exp(-(E_i - min E) / temperature)`` of fits with energies ``E`` (nats)."""
    E = np.asarray(energies, float).reshape(-1)
    if E.size == 0 or not np.all(np.isfinite(E)):
        raise InputError(f"energies: expected finite values, got {E.tolist()}")
    if not float(temperature) > 0:
        raise InputError(f"temperature: expected > 0 nats, got {temperature!r}")
    w = np.exp(-(E - E.min()) / float(temperature))
    return w / w.sum()


def ranking_energies(method: str, hypotheses, category: str | None = None) -> list[float]:
    """The energies (nats) that weight ``method``'s ``hypotheses`` (:class:`ShapeHypothesis`) of an object of
    ``category``: their plain energies for :data:`PLAIN_RANKED_METHODS` (InputError if one is missing); for a
    category in :data:`COVERAGE_RANKED_CATEGORIES`, the fits' own plus :data:`UNCOVERED_NATS` per uncovered
    observed point; else the fits' own."""
    if check_method(method) not in PLAIN_RANKED_METHODS:
        per_point = UNCOVERED_NATS if category in COVERAGE_RANKED_CATEGORIES else 0.0
        return [float(h.energy) + per_point * int(h.uncovered) for h in hypotheses]
    plain = [float(h.plain_energy) for h in hypotheses]
    if not np.all(np.isfinite(plain)):
        raise InputError(f"the {method} method weights its shape hypotheses by their plain energies: "
                         "estimate them with plain_energies=True")
    return plain


def grasp_candidates(method: str, model: CategoryModel, hypotheses, *, temperature: float = POSTERIOR_TEMPERATURE,
                     radius: float = SUPPORT_RADIUS_M) -> list[GraspCandidate]:
    """``method``'s grasp for each :class:`ShapeHypothesis` (energy order), ranked by support (module docstring).

    Ties in support keep the energy order, so with one hypothesis, or
    hypotheses whose grasps all land apart, the MAP fit's grasp comes first.
    The weights come from :func:`ranking_energies`.
    """
    hypotheses = list(hypotheses)
    if not hypotheses:
        raise InputError("hypotheses: expected at least one shape hypothesis")
    w = hypothesis_weights(ranking_energies(method, hypotheses, model.category), temperature)
    motions = [predict_motion(method, model, h.x, h.X_WO, h.scale)[0] for h in hypotheses]
    f = np.array([motion_functional_point(m, model.grasp_anchor_H) for m in motions])
    near = np.linalg.norm(f[:, None] - f[None], axis=2) <= float(radius)
    support = near.astype(float) @ w
    out = [GraspCandidate(m, np.asarray(h.completed_W, float), i, float(w[i]), float(support[i]), f[i])
           for i, (m, h) in enumerate(zip(motions, hypotheses))]
    return sorted(out, key=lambda c: -c.support)  # stable: ties keep the energy order
