"""Latent shape + pose inference (paper eq. 15, Alg. 2 line 1): the latent shape estimator.

Given an observed cloud O (N, 3) (full or a single view, noisy, with
outliers) and a :class:`~catgrasp_drake.core.shape_space.ShapeSpace`, find the
latent vector x and a similarity theta = (R, t, s) such that the completed
shape

    Y(x) = C + G W(x) = C + V0 + sum_j x_j B_j          (linear in x)
    T(x, theta) = s R Y(x) + t                          (observation frame)

explains O. As in CPD, the model points are the centres of an isotropic
Gaussian mixture (variance sigma2) plus a uniform outlier density ``w / V``
(V = volume of O's bounding box, padded 1 cm), and we minimise

    E(x, theta, sigma2) = -sum_n log p(o_n) + prior / 2 |x|^2

(eq. 15 in the CPD direction, plus an N(0, I) prior on the whitened latent x)
by EM instead of the paper's gradient descent: the E-step gives posteriors
P; the M-step is closed-form -- a weighted Procrustes with scale for theta
(the same as rigid CPD) and, because Y is linear in x, a q x q linear solve
``(s^2/sigma2 H + prior I) x = s^2/sigma2 g`` for x -- then sigma2 in closed
form (the EM loop :func:`catgrasp_drake.core.em.em_loop`, shared with CPD).
Each step cannot increase E (between visibility updates, which change the
mixture), so no step size is needed; ~1.5 ms per iteration for a 500-point
model and 500 observed points, 190x faster than L-BFGS with analytic
gradients on the same energy (benchmarks/bench_inference.py).

Visibility-aware E-step (``camera_position`` given, in the observation
frame): only the model points visible from the camera under the current
pose (hidden-point removal on T, recomputed every ``visibility_every`` = 4
iterations: same accuracy as every 1-2, measured) are mixture centres; hidden
ones still move with x and theta. Without it, on a single view the model's
unseen side is dragged onto the visible data.

Yaw search: the object stands on a table (z up in the observation frame);
``yaw_candidates=n`` starts from n yaws about the model's vertical axis
(``R = R0 rotz(yaw)``), each with centroid matching (of the visible part of
the model), runs a short fit on a subsample of O, keeps the lowest energy and
refines it to convergence on the full cloud. Pruned early: after
``prune_iter`` = 2 iterations only the lower half of the energies go on
(``yaw_keep`` = "half": 4 of 8; keeping 4 of 12 lost the yaw on real drills)
(the kept starts' results are those of the unpruned search; accuracy
against the unpruned search: benchmarks/bench_inference.py). The search's E-step runs in float32 while the
rounding bound allows (:data:`SEARCH_F32_TOL`); in the refine, a scheduled
visibility update is skipped while no model point has moved more than
``visibility_move`` = 2 mm since the last (hidden-point removal is ~40 % of
the fit's time otherwise). :data:`LEGACY_SEARCH` restores the earlier settings.

Confidence (in [0, 1]): with ``tau`` = the mean nearest-neighbour spacing of
the completed model, ``inlier = mean_n exp(-d(o_n, model)^2 / (2 tau^2))``
(observed points explained) and ``coverage = mean_m exp(-d(t_m, O)^2 / (2 tau^2))``
over the visible model points (model not contradicted by missing data);
``confidence = sqrt(inlier * coverage)``. Measured: ~1.0 for a noise-free
exact fit, 0.3-0.55 for held-out real drills seen from one view (the shape
space's ~6-8 mm error against a ~5 mm point spacing), 0.73 with 50 % uniform
outliers (tests); a wrong yaw or a wrong shape lowers it.
"""

from __future__ import annotations

import dataclasses
import math
import time
from concurrent.futures import ThreadPoolExecutor
from contextlib import nullcontext
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from scipy.spatial import cKDTree

from catgrasp_drake.core.cpd import EPS32, estep, exponent_bound, initial_sigma2, nonrigid_cpd, weighted_procrustes
from catgrasp_drake.core.deformation import deform_points, warp_poses
from catgrasp_drake.core.em import MStep, em_loop
from catgrasp_drake.core.kernels import kernel_width
from catgrasp_drake.core.rotations import orthonormalize, rotz
from catgrasp_drake.core.shape_space import ShapeSpace
from catgrasp_drake.core.threads import n_threads, single_threaded_blas
from catgrasp_drake.core.validation import (
    as_points,
    count,
    non_negative,
    outlier_weight,
    positive,
    real_array,
    real_number,
    vector3,
)
from catgrasp_drake.core.visibility import DEFAULT_RADIUS_FACTOR, MAX_RADIUS_FACTOR, hidden_point_removal
from catgrasp_drake.errors import InputError

SIGMA2_MIN_M2 = 1e-8  # (0.1 mm)^2
#: Smallest E-step (visible model points x observed points) split over the thread pool: below it the
#: threads' hand-offs cost more than they save (quiet 2 cores, ``cpd.estep``: 400 x 420 0.36 ms in one
#: thread vs 0.52 ms pooled; 786 x 600 1.29 vs 1.18 ms; 2000 x 2000 10.7 vs 6.4 ms). The camera's clouds
#: (~400 x 420) stay in one thread: the diagram's fit 155 -> 133 ms median (issue 17).
THREADED_ESTEP_MIN = 500_000

#: Most yaw starts of the search (one per 1 degree).
MAX_YAW_CANDIDATES = 360
#: The yaw search's E-step runs in float32 while the rounding bound of its exponents,
#: ``8 eps32`` :func:`~catgrasp_drake.core.cpd.exponent_bound`, is at most this (relative error of a
#: kernel value); float64 beyond. (The refine stays float64: float32 energies there stopped the
#: tolerance test from firing, 28 -> 37 iterations on the camera's drills, measured.)
SEARCH_F32_TOL = 1e-3
#: The search and refine settings before the speed work of issue 17 (bench_transfer.py and
#: bench_inference.py compare against them): every start searched to the end, two hidden-point removals
#: per start, float64 throughout, the visibility recomputed on schedule however little the model moved.
LEGACY_SEARCH = {"yaw_keep": None, "recenter_visibility": True, "search_float32": False, "visibility_move": 0.0,
                 "kernel32": False}
#: Shape hypotheses (``hypotheses`` > 1) whose energy, after DROP_AFTER refine iterations, is more than
#: DROP_ENERGY nats above the lowest are not refined further. Chosen on the committed instances (3 views each,
#: 3 hypotheses; ``python benchmarks/results/experiments/s34_hypothesis_drop/probe.py``): from iteration 16
#: to the end the gap between a hypothesis and the best closed by at most 126 nats (from iteration 8: 328, and
#: a spray-bottle hypothesis 328 nats behind there became the best), and a dropped hypothesis ended at least
#: 150 nats behind, a posterior weight below 1e-4 (``prediction.POSTERIOR_TEMPERATURE`` 15 nats). The MAP fit
#: and every grasp candidate of weight above 1e-3 were unchanged on all 135 views. On drills and spray bottles
#: the other hypotheses sit 150-450 nats behind and are dropped; on mugs (5-60 nats) none is.
DROP_ENERGY = 200.0
DROP_AFTER = 16


@dataclass(frozen=True, eq=False)
class InferenceResult:
    """Latent shape and similarity pose of an observed instance.

    ``completed = s * (C + G W(x)) @ R.T + t`` (M, 3) in the observation frame;
    ``R`` proper rotation, ``t`` (3,) m, ``s`` uniform scale (the canonical
    frame scaled by ``s`` then rotated and translated: a similarity, not a
    rigid pose); ``energy`` the final E; ``sigma2`` (m^2); ``visible`` (M,)
    mask of the model points that were mixture centres at the end (all True
    without a camera); ``timing`` seconds (``total``, ``search``, ``refine``,
    ``residual``); ``yaw`` the winning start's yaw (rad). ``hypotheses``: with
    ``infer_latent_pose(hypotheses=k)``, the distinct refined fits, lowest
    energy first (this result is the first, without its own ``hypotheses``);
    empty otherwise. ``plain_energy`` (nats): with ``hypotheses`` > 1 and
    ``plain_energies``, eq. 15's
    energy of this fit with every model point a mixture centre (no visibility
    model), at the best fit's sigma2 on the same observed points (at most
    :data:`PLAIN_ENERGY_POINTS` of the refine's; :func:`plain_energy`), so that
    hypotheses compare; NaN otherwise.
    """

    x: np.ndarray
    R: np.ndarray
    t: np.ndarray
    s: float
    energy: float
    confidence: float
    completed: np.ndarray
    sigma2: float
    iterations: int
    converged: bool
    yaw: float
    visible: np.ndarray
    timing: dict
    diagnostics: dict = field(default_factory=dict)
    space: ShapeSpace | None = field(default=None, repr=False)
    residual_W: np.ndarray | None = field(default=None, repr=False)
    hypotheses: tuple = field(default=(), repr=False)
    plain_energy: float = math.nan

    @property
    def X_OC(self) -> np.ndarray:
        """4x4 similarity canonical -> observation: ``[[s R, t], [0, 1]]``."""
        X = np.eye(4)
        X[:3, :3] = self.s * self.R
        X[:3, 3] = self.t
        return X

    def transform_points(self, points_canonical) -> np.ndarray:
        """Apply the similarity only (no deformation) to canonical-frame points."""
        p = as_points(points_canonical, "points", min_points=0)
        return self.s * p @ self.R.T + self.t

    def deform_points(self, points_canonical) -> np.ndarray:
        """Canonical-frame points -> observation frame through W(x) then the similarity."""
        if self.space is None:
            raise InputError("this InferenceResult carries no shape space")
        p = deform_points(self.space.canonical, self.space.decode(self.x), self.space.beta, points_canonical)
        return self.transform_points(p)

    def warp_poses(self, X_canonical) -> np.ndarray:
        """Canonical control poses (K, 4, 4) -> observation frame (Alg. 2 line 3).

        Warped by the deformation (rotations re-orthonormalised, det +1), then
        position ``s R p + t`` and rotation ``R R_p`` (the scale does not
        change orientations).
        """
        if self.space is None:
            raise InputError("this InferenceResult carries no shape space")
        Xw = warp_poses(self.space.canonical, self.space.decode(self.x), self.space.beta, X_canonical)
        single = Xw.ndim == 2
        Xw = Xw[None] if single else Xw
        out = Xw.copy()
        out[:, :3, :3] = self.R @ Xw[:, :3, :3]
        out[:, :3, 3] = self.s * Xw[:, :3, 3] @ self.R.T + self.t
        return out[0] if single else out


@dataclass
class _State:
    x: np.ndarray
    R: np.ndarray
    t: np.ndarray
    s: float
    sigma2: float
    energy: float = math.inf
    iterations: int = 0
    converged: bool = False
    visible: np.ndarray | None = None
    yaw: float = 0.0
    T_visible: np.ndarray | None = None  # the model points (observation frame) where ``visible`` was computed


class _Fit(NamedTuple):
    """The parameters :meth:`_Problem.run` passes through the EM loop: latent ``x``, similarity ``(R, t, s)``,
    the model ``Y = model(x)`` (canonical frame) and ``T = s Y R^T + t`` (observation frame, m)."""

    x: np.ndarray
    R: np.ndarray
    t: np.ndarray
    s: float
    Y: np.ndarray
    T: np.ndarray


class _Problem:
    """Precomputed linear model and options for one observation."""

    def __init__(self, space, O, camera, w, prior, scale_bounds, radius_factor, fit_scale, upright):
        self.space = space
        V0, B = space.displacement_basis
        self.a = space.canonical + V0  # (M, 3)
        self.B = B  # (q, M, 3)
        self.Bf = np.ascontiguousarray(B.reshape(space.q, -1).T)  # (3M, q)
        self.Bm = self.Bf.reshape(space.n_points, 3, space.q)  # (M, 3, q): a point's rows by fancy index
        self.M = space.n_points
        self.q = space.q
        self.O = O
        self.camera = camera
        self.w = w
        self.prior = prior
        self.scale_bounds = scale_bounds
        self.radius_factor = radius_factor
        self.fit_scale = fit_scale
        self.upright = upright
        ext = O.max(0) - O.min(0) + 0.02
        self.log_volume = float(np.log(max(float(np.prod(ext)), 1e-9)))

    def model(self, x):
        return self.a + (self.Bf @ x).reshape(self.M, 3)

    def visible(self, T):
        if self.camera is None:
            return np.ones(self.M, dtype=bool)
        vis = hidden_point_removal(T, self.camera[0], radius_factor=self.radius_factor)
        for c in self.camera[1:]:  # several views: visible from any of the cameras
            vis = vis | hidden_point_removal(T, c, radius_factor=self.radius_factor)
        return vis

    def log_uniform(self, n_vis, sigma2):
        if self.w <= 0.0:
            return None
        return (math.log(self.w / (1.0 - self.w)) + math.log(n_vis) + 1.5 * math.log(2 * math.pi * sigma2)
                - self.log_volume)

    def fit(self, x, R, t, s) -> _Fit:
        """The parameters ``(x, R, t, s)`` with their model ``Y`` (canonical frame) and its pose ``T`` (m)."""
        Y = self.model(x)
        return _Fit(x, R, t, s, Y, s * Y @ R.T + t)

    def mstep(self, e, idx, fit: _Fit, O, sigma2) -> _Fit:
        """Closed-form M-step for the posteriors ``e`` of the model points ``idx`` on the observed points ``O``
        (m): the pose (weighted Procrustes, scale clamped to the bounds) given ``fit.x``, then ``x`` given the
        pose, ``(s^2/sigma2 H + prior I) x = s^2/sigma2 g`` (``x`` unchanged if singular)."""
        x = fit.x
        Yv = fit.Y[idx]
        R, t, s, _ = weighted_procrustes(e.PX, e.P1, e.Pt1, e.Np, O, Yv, scale=self.fit_scale, upright=self.upright)
        if self.fit_scale:
            s_clamped = float(np.clip(s, *self.scale_bounds))
            if s_clamped != s:
                s = s_clamped
                mu_x = (e.Pt1 @ O) / e.Np
                mu_y = (e.P1 @ Yv) / e.Np
                t = mu_x - s * R @ mu_y
        if self.q > 0:
            P1 = e.P1
            Bv = self.Bm[idx].reshape(-1, self.q)  # (3m, q), rows point-major
            H = Bv.T @ (Bv * np.repeat(P1, 3)[:, None])
            Z = (e.PX - P1[:, None] * t) @ R / s  # = P1 * z  (model frame)
            g = Bv.T @ (Z - P1[:, None] * self.a[idx]).reshape(-1)
            c = s * s / sigma2
            A = c * H + self.prior * np.eye(self.q)
            try:
                x = np.linalg.solve(A, c * g)
            except np.linalg.LinAlgError:
                pass
        return self.fit(x, R, t, float(s))

    def run(self, st: _State, O, n_iter, tol, vis_every=1, pool=None, k_start=0, float32=False, vis_move=0.0,
            kernel32=False):
        """EM iterations ``k_start .. n_iter - 1`` from state ``st`` on observation subset O.

        ``k_start`` > 0 resumes a run stopped after ``k_start`` iterations (its
        last energy, visibility and where it was computed are the state's): the
        result is that of one uninterrupted run. ``float32``: the E-step in float32 while
        :data:`SEARCH_F32_TOL` allows. ``vis_move`` (m) > 0: a scheduled
        visibility update is skipped while no model point has moved more than
        that since the last one. ``kernel32``: every float64 E-step evaluates its kernel in float32
        (``cpd.estep(kernel32=True)``).
        """
        N = len(O)
        fit = self.fit(st.x, st.R, st.t, st.s)
        resume = k_start > 0 and st.visible is not None
        vis = st.visible if st.visible is not None else self.visible(fit.T)
        T_vis = st.T_visible if resume and st.T_visible is not None else fit.T
        idx = None
        if float32:
            ctr = O.mean(axis=0)
            Oc = O - ctr

        def e_step(k, m, sigma2):  # over the model points visible at m.params.T
            nonlocal vis, T_vis, idx
            T = m.params.T
            if k > 0 and vis_every and k % vis_every == 0:
                if not (vis_move > 0.0 and float(np.abs(T - T_vis).max()) < vis_move):
                    vis = self.visible(T)
                    T_vis = T
            idx = np.flatnonzero(vis)
            if len(idx) < 3:
                vis = np.ones(self.M, dtype=bool)
                idx = np.arange(self.M)
            Tv = T[idx]
            dtype = np.float64
            if float32 and 8.0 * EPS32 * exponent_bound(Tv - ctr, Oc, sigma2) <= SEARCH_F32_TOL:
                dtype = np.float32
            return estep(Tv, O, sigma2, self.w, log_uniform=self.log_uniform(len(idx), sigma2),
                         pool=pool if len(idx) * N >= THREADED_ESTEP_MIN else None, dtype=dtype, kernel32=kernel32)

        def m_step(e, m, sigma2):
            fit = self.mstep(e, idx, m.params, O, sigma2)
            return MStep(fit.T[idx], 0.5 * self.prior * float(fit.x @ fit.x), fit)

        start = MStep(fit.T, 0.5 * self.prior * float(st.x @ st.x), fit)
        r = em_loop(O, e_step, m_step, start, st.sigma2, n_iter=n_iter, tol=tol, sigma2_floor=SIGMA2_MIN_M2,
                    stop_at_floor=False, min_mass=1e-9, k_start=k_start,
                    f_prev=st.energy if resume else math.inf)
        st.x, st.R, st.t, st.s = r.m.params[:4]
        st.sigma2 = r.sigma2
        if r.e is not None:
            st.energy = r.objective
        st.iterations += r.iterations
        st.converged = st.converged or r.converged
        st.visible, st.T_visible = vis, T_vis
        return st


def _parse_initial_pose(initial_pose):
    if initial_pose is None:
        return np.eye(3), None, 1.0
    if isinstance(initial_pose, tuple) and len(initial_pose) == 3:
        R, t, s = initial_pose
        R = real_array(R, "initial_pose: R", "3x3 rotation")
        if R.shape != (3, 3):
            raise InputError(f"initial_pose: R must be a 3x3 rotation, got shape {R.shape}")
        R = orthonormalize(R)
        t = vector3(t, "initial_pose translation")
        s = positive(s, "initial_pose scale")
        return R, t, s
    X = real_array(initial_pose, "initial_pose", "4x4 matrix or (R, t, s)")
    if X.shape != (4, 4) or not np.all(np.isfinite(X)):
        raise InputError(f"initial_pose: expected a finite 4x4 matrix or (R, t, s), got shape {X.shape}")
    A = X[:3, :3]
    det = float(np.linalg.det(A))
    if not det > 1e-12:
        raise InputError("initial_pose: the 3x3 block must have a positive determinant")
    s = det ** (1.0 / 3.0)
    return orthonormalize(A / s), vector3(X[:3, 3], "initial_pose translation"), positive(s, "initial_pose scale")


def _yaws(yaw_candidates):
    if yaw_candidates is None:
        return np.zeros(1)
    if np.isscalar(yaw_candidates):
        n = count(yaw_candidates, "yaw_candidates", 1, MAX_YAW_CANDIDATES)
        return 2.0 * np.pi * np.arange(n) / n
    try:
        y = real_array(yaw_candidates, "yaw_candidates", "list of yaws").reshape(-1)
    except InputError:
        y = np.zeros(0)
    if len(y) == 0 or len(y) > MAX_YAW_CANDIDATES or not np.all(np.isfinite(y)):
        raise InputError(f"yaw_candidates: expected an int in [1, {MAX_YAW_CANDIDATES}] or a non-empty list of at most "
                         f"{MAX_YAW_CANDIDATES} finite yaws (rad)")
    return y


def _subsample(O, n_max):
    if len(O) <= n_max:
        return O
    step = len(O) / n_max
    return O[(np.arange(n_max) * step).astype(int)]


def model_spacing(space: ShapeSpace) -> float:
    """Mean nearest-neighbour distance (m) of the space's canonical points (its point spacing)."""
    if not isinstance(space, ShapeSpace):
        raise InputError(f"space: expected a ShapeSpace, got {type(space).__name__}")
    if space.n_points < 2:
        return 0.0
    d, _ = cKDTree(space.canonical).query(space.canonical, k=2)
    return float(d[:, 1].mean())


def camera_positions(camera_position) -> np.ndarray:
    """``camera_position`` (3,) or (K, 3) as a (K, 3) array of finite positions, or InputError."""
    try:
        one = np.ndim(camera_position) == 1
    except ValueError:  # ragged nesting: as_points names it
        one = False
    if one:
        return vector3(camera_position, "camera_position")[None]
    return as_points(camera_position, "camera_position", min_points=1)


def _confidence(completed, visible, O):
    d_model, _ = cKDTree(completed).query(completed, k=2)
    tau = max(float(d_model[:, 1].mean()), 1e-6)
    d_obs, _ = cKDTree(completed).query(O)
    inlier = float(np.exp(-(d_obs**2) / (2 * tau**2)).mean())
    vis_pts = completed[visible] if np.any(visible) else completed
    d_vis, _ = cKDTree(O).query(vis_pts)
    coverage = float(np.exp(-(d_vis**2) / (2 * tau**2)).mean())
    return math.sqrt(inlier * coverage), inlier, coverage, tau


def infer_latent_pose(
    space: ShapeSpace,
    observed,
    *,
    camera_position=None,
    yaw_candidates=None,
    initial_pose=None,
    max_iter: int = 40,
    tol: float = 1e-4,
    w: float = 0.05,
    prior: float = 1.0,
    fit_scale: bool = True,
    scale_bounds: tuple[float, float] = (0.5, 2.0),
    search_iter: int = 12,
    search_points: int = 250,
    yaw_keep: int | str | None = "half",
    prune_iter: int = 2,
    recenter_visibility: bool = False,
    search_float32: bool = True,
    kernel32: bool = True,
    visibility_move: float = 2e-3,
    max_points: int = 600,
    visibility_every: int = 4,
    radius_factor: float = DEFAULT_RADIUS_FACTOR,
    sigma2_init: float | None = None,
    residual_cpd: bool = False,
    residual_beta: float | None = None,
    residual_lam: float = 3.0,
    hypotheses: int = 1,
    upright: bool = False,
    fit_threads: int | None = 1,
    drop_energy: float | None = DROP_ENERGY,
    drop_after: int = DROP_AFTER,
    plain_energies: bool = False,
    reseed: bool = False,
) -> InferenceResult:
    """Fit latent x and a similarity (R, t, s) of ``space`` to ``observed`` (N, 3), metres.

    ``camera_position`` (3,) in the observation frame turns on the
    visibility-aware E-step; (K, 3): the observation merges K views, and a
    model point is visible when any of the K cameras sees it. ``yaw_candidates``: None (one start), an int n
    (n yaws evenly spaced in [0, 2 pi)) or a list of yaws (rad).
    ``initial_pose``: 4x4 (may contain a scale) or ``(R, t, s)``; its rotation
    is the base of the yaw search; without it the observation frame is
    assumed to be the canonical orientation (z up). Starts use centroid
    matching unless ``initial_pose`` is given and ``yaw_candidates`` is None.
    ``w`` outlier weight; ``prior`` weight of the N(0, I) prior on x (0
    disables); ``search_iter``/``search_points``: iterations and observation
    subsample of each start of the yaw search; ``max_points``: larger
    observations are subsampled (deterministic stride) for the EM -- the
    model has ~500 points, so more data adds time, not accuracy (measured in
    bench_inference.py); the confidence uses every point; ``sigma2_init`` caps
    the initial variance (m^2; default: the data estimate -- a 2 cm cap cost
    0.5 mm of unseen-part error on the drills); ``visibility_every``: hidden
    points are recomputed every that many iterations (in the refine, not while
    no model point moved more than ``visibility_move`` m since the last time;
    0 = always). ``yaw_keep`` (None = all; "half" = half the starts, rounded up) starts survive ``prune_iter``
    iterations of the search; the rest stop there (``start_energies`` in the
    diagnostics then mixes energies after ``prune_iter`` and ``search_iter``
    iterations). ``recenter_visibility``: recompute each start's visible part
    after its centroid matching (one more hidden-point removal per start).
    ``search_float32``: the search's E-step in float32 where accurate enough
    (:data:`SEARCH_F32_TOL`). ``kernel32``: every other E-step (the refine's, the search's beyond that bound)
    computes its exponents in float64 and their ``exp`` in float32 (``cpd.estep(kernel32=True)``: each kernel
    value within 6e-6 relative of float64's; the E-step 2x faster, most of the fit's time). ``residual_cpd`` adds a
    non-rigid CPD (kernel ``residual_beta``, default the space's beta) from the
    visible completed points to O after the fit and moves the visible points
    only (visible surface detail; applied to the hidden points through its
    field it dragged them toward the data: unseen-part error 9.4 -> 12.0 mm
    on the real drills). ``hypotheses`` = k > 1: the k lowest-energy starts
    of the yaw search (those kept after pruning) are each refined to
    convergence, and the lowest final energy wins (the search's energies on a
    subsample after ``search_iter`` iterations do not always rank the final
    fits in order); the distinct refined fits (:data:`SAME_MODE_DEG`,
    :data:`SAME_MODE_M`) are the result's ``hypotheses``, for a grasp chosen
    across them. 1: the search's best start only (the earlier behaviour).
    ``upright``: the rotation stays about the observation frame's z axis (the object stands on a table whose
    normal is that z; ``initial_pose``'s rotation should then be a yaw too): every M-step's Procrustes is
    restricted to a yaw (:func:`~catgrasp_drake.core.cpd.weighted_procrustes`). False: a free rotation, the
    paper's 7-parameter similarity. ``fit_threads``: threads that run the search's starts and the refined
    hypotheses side by side (1, the default: one after another; None: one per core, at most 4). The result
    is the same to the bit whatever the count. Measured on the camera's clouds (``bench_transfer.py
    --settings new parallel``, 2 cores): 4-12 % faster on a quiet machine, 2x slower when another process
    keeps the cores busy (each EM iteration is hundreds of small numpy calls, bound by the interpreter).
    ``drop_energy`` (nats; None: never) and ``drop_after``: with ``hypotheses`` > 1, every hypothesis is refined
    ``drop_after`` iterations first; those whose energy is then more than ``drop_energy`` above the lowest stop
    there (their result is that unfinished fit), the others are refined on, each exactly as without the pause
    (:data:`DROP_ENERGY`: the best fit and every hypothesis that keeps a posterior weight are unchanged).
    ``plain_energies``: with ``hypotheses`` > 1, each hypothesis also gets its ``plain_energy``
    (:func:`plain_energy`; about 2 ms each), for a posterior weighted by the paper's plain likelihood.
    ``reseed``: with ``hypotheses`` > 1, every hypothesis but the lowest-energy one is refined once more from
    the best fit's shape (its latent x and scale) at the hypothesis' own rotation and translation, and the
    lower-energy of its two fits is kept, so no energy rises: a start that settled on a poor shape at its yaw
    gets the shape the data supports elsewhere. Up to ``hypotheses`` - 1 more refines (mugs: about +20 % of the
    fit's time; used for the categories in ``prediction.RESEEDED_CATEGORIES``).
    """
    t0 = time.perf_counter()
    if not isinstance(space, ShapeSpace):
        raise InputError(f"space: expected a ShapeSpace, got {type(space).__name__}")
    O = as_points(observed, "observed", min_points=3, check_units=True)
    camera = None if camera_position is None else camera_positions(camera_position)
    w = outlier_weight(w)
    prior = non_negative(prior, "prior")
    try:
        lo, hi = (real_number(v, "scale_bounds") for v in scale_bounds)
    except (TypeError, ValueError):  # not a pair (InputError, a ValueError, is re-raised below)
        lo = hi = float("nan")
    if not (0 < lo <= 1.0 <= hi):
        raise InputError(f"scale_bounds: expected a pair 0 < low <= 1 <= high, got {scale_bounds!r}")
    R0, t0_given, s0 = _parse_initial_pose(initial_pose)
    yaws = _yaws(yaw_candidates)
    max_iter = count(max_iter, "max_iter", 1)
    tol = non_negative(tol, "tol")
    search_iter = count(search_iter, "search_iter", 1)
    search_points = count(search_points, "search_points", 3)
    if isinstance(yaw_keep, str):
        if yaw_keep != "half":
            raise InputError(f"yaw_keep: expected 'half', None or a count, got {yaw_keep!r}")
        yaw_keep = max(1, -(-len(yaws) // 2))
    elif yaw_keep is not None:
        yaw_keep = count(yaw_keep, "yaw_keep", 1, MAX_YAW_CANDIDATES)
    prune_iter = count(prune_iter, "prune_iter", 1)
    visibility_move = non_negative(visibility_move, "visibility_move")
    for name, flag in (("recenter_visibility", recenter_visibility), ("search_float32", search_float32),
                       ("kernel32", kernel32), ("upright", upright)):
        if not isinstance(flag, (bool, np.bool_)):
            raise InputError(f"{name}: expected True or False, got {flag!r}")
    max_points = count(max_points, "max_points", 3)
    visibility_every = count(visibility_every, "visibility_every", 0)
    radius_factor = positive(radius_factor, "radius_factor")
    if not 1.0 < radius_factor <= MAX_RADIUS_FACTOR:
        raise InputError(f"radius_factor: must be in (1, {MAX_RADIUS_FACTOR:g}], got {radius_factor}")
    if sigma2_init is not None:
        sigma2_init = positive(sigma2_init, "sigma2_init")
    if residual_cpd:
        if residual_beta is not None:
            residual_beta = kernel_width(residual_beta, "residual_beta")
        residual_lam = positive(residual_lam, "residual_lam")
    n_hypotheses = count(hypotheses, "hypotheses", 1, MAX_YAW_CANDIDATES)
    if drop_energy is not None:
        drop_energy = positive(drop_energy, "drop_energy")
    drop_after = count(drop_after, "drop_after", 1)
    fit_threads = n_threads() if fit_threads is None else count(fit_threads, "fit_threads", 1, 64)
    prob = _Problem(space, O, camera, w, prior, (lo, hi), radius_factor, bool(fit_scale), bool(upright))

    # the starts of the yaw search and the refined hypotheses are independent fits: with fit_threads > 1 they
    # run side by side (each is computed exactly as alone, so the result does not depend on the count)
    with single_threaded_blas(), ThreadPoolExecutor(fit_threads) if fit_threads > 1 else nullcontext() as fits:
        each = fits.map if fit_threads > 1 else map
        x0 = np.zeros(space.q)
        c_obs = O.mean(axis=0)
        Y0 = prob.model(x0)

        def start(yaw):
            R = R0 @ rotz(yaw)
            if t0_given is not None and yaw_candidates is None:
                t = t0_given
            else:
                t = c_obs - s0 * R @ Y0.mean(axis=0)
                if camera is not None:  # match the centroid of the part the camera would see
                    vis = prob.visible(s0 * Y0 @ R.T + t)
                    t = c_obs - s0 * R @ Y0[vis].mean(axis=0)
            T = s0 * Y0 @ R.T + t
            if camera is None or recenter_visibility or (t0_given is not None and yaw_candidates is None):
                vis = prob.visible(T)  # (else: the part matched above; the search updates it on schedule)
            s2 = max(initial_sigma2(T[vis], O), SIGMA2_MIN_M2)
            if sigma2_init is not None:
                s2 = min(s2, sigma2_init)
            return _State(x=x0.copy(), R=R, t=t, s=s0, sigma2=s2, visible=vis, yaw=float(yaw))

        # ---- search over yaw on a subsample
        start_energies = []
        if len(yaws) > 1:
            O_sub = _subsample(O, search_points)
            vis_every = max(1, 2 * visibility_every)
            k_prune = search_iter if yaw_keep is None or yaw_keep >= len(yaws) else min(prune_iter, search_iter)
            f32, k32 = bool(search_float32), bool(kernel32)
            states = list(each(lambda yaw: prob.run(start(yaw), O_sub, k_prune, 0.0, vis_every=vis_every,
                                                        float32=f32, kernel32=k32), yaws))
            start_energies = [st.energy for st in states]
            if k_prune < search_iter:  # only the yaw_keep lowest energies go on (stable order: ties keep the first)
                kept = sorted(np.argsort(start_energies, kind="stable")[:yaw_keep])
                list(each(lambda i: prob.run(states[i], O_sub, search_iter, 0.0, vis_every=vis_every,
                                                 k_start=k_prune, float32=f32, kernel32=k32), kept))
                for i in kept:
                    start_energies[i] = states[i].energy
                states = [states[i] for i in kept]
            order = np.argsort([st.energy for st in states], kind="stable")  # ties keep the first
            refine_first = [states[i] for i in order[:n_hypotheses]]
            for st in refine_first:
                st.iterations = 0
                st.converged = False
        else:
            refine_first = [start(yaws[0])]
        t_search = time.perf_counter() - t0
        # ---- refine (on at most max_points observed points): the best start, or the ``hypotheses`` best
        O_fit = _subsample(O, max_points)
        # a pool even on one core: whether the E-step is split into blocks must not depend on the machine
        pool = ThreadPoolExecutor(n_threads())
        dropping = drop_energy is not None and len(refine_first) > 1 and drop_after < max_iter
        first_iter = drop_after if dropping else max_iter

        def refine(st, n_iter, k_start=0):  # iterations k_start .. n_iter - 1; from 0 with fresh visibility
            if k_start == 0:
                st.visible = None
            return prob.run(st, O_fit, n_iter, tol, vis_every=visibility_every, pool=pool, vis_move=visibility_move,
                            k_start=k_start, kernel32=bool(kernel32))

        try:
            list(each(lambda st: refine(st, first_iter), refine_first))
            if dropping:  # hypotheses far behind the best stop here; the rest go on exactly as if never paused
                best_energy = min(st.energy for st in refine_first)
                go_on = [st for st in refine_first if not st.converged and st.energy <= best_energy + drop_energy]
                list(each(lambda st: refine(st, max_iter, first_iter), go_on))
            finished = list(each(lambda rank: _finish(prob, refine_first[rank], O, w, space, residual_cpd,
                                                      residual_beta, residual_lam, rank), range(len(refine_first))))
            if reseed and len(finished) > 1:  # the others again from the best fit's shape, at their own pose
                b = min(range(len(finished)), key=lambda i: finished[i].energy)  # ties: the search's order
                others = [i for i in range(len(finished)) if i != b]
                again = [_State(x=finished[b].x.copy(), R=finished[i].R, t=finished[i].t, s=finished[b].s,
                                sigma2=finished[i].sigma2, yaw=finished[i].yaw) for i in others]
                list(each(lambda st: refine(st, max_iter), again))
                redone = list(each(lambda j: _finish(prob, again[j], O, w, space, residual_cpd, residual_beta,
                                                     residual_lam, others[j]), range(len(others))))
                for i, r in zip(others, redone):
                    if r.energy < finished[i].energy:
                        finished[i] = r
        finally:
            if pool is not None:
                pool.shutdown()
    t_done = time.perf_counter() - t0
    finished.sort(key=lambda r: r.energy)  # stable: ties keep the search's order
    distinct = []
    for r in finished:
        if not any(_same_mode(r, d) for d in distinct):
            distinct.append(r)
    timing = {"total": t_done, "search": t_search, "refine": t_done - t_search - sum(r.timing["residual"]
                                                                                     for r in distinct),
              "residual": sum(r.timing["residual"] for r in distinct)}
    if plain_energies and n_hypotheses > 1:  # they compare the hypotheses at one sigma2, the best fit's
        O_plain = _subsample(O_fit, PLAIN_ENERGY_POINTS)
        distinct = [dataclasses.replace(r, plain_energy=plain_energy(prob, r, O_plain, distinct[0].sigma2))
                    for r in distinct]
    best = dataclasses.replace(distinct[0], timing=timing)
    best.diagnostics["start_energies"] = [float(e) for e in start_energies]
    if n_hypotheses > 1:
        best = dataclasses.replace(best, hypotheses=(best,) + tuple(distinct[1:]))
    return best


def plain_energy(prob: _Problem, r: InferenceResult, O: np.ndarray, sigma2: float) -> float:
    """Eq. 15's energy (nats, up to a constant shared by every fit at this ``sigma2`` on ``O``) of the latent
    fit ``r`` with EVERY model point a mixture centre, as in the paper's plain fit: the negative
    log-likelihood of the observed points ``O`` (N, 3, m) under the GMM at ``sigma2`` (m^2) with the fit's
    outlier weight, plus the prior's ``0.5 prior |x|^2``.

    The visibility-aware E-step leaves model points the camera cannot see free, so a drill turned round can
    explain one view about as well as the right fit; here its unseen model points still pull on the data.
    Ranking the hypotheses by it (the ``latent_plain`` method) turned no validation drill round where the
    visibility-aware energy turned 4 of 144 views, but on a large real drill it prefers the turned fit
    (``benchmarks/results/experiments/s45_yaw_rank``)."""
    T = r.s * prob.model(r.x) @ r.R.T + r.t
    e = estep(T, O, sigma2, prob.w, log_uniform=prob.log_uniform(prob.M, sigma2))
    return float(e.nll + 0.5 * prob.prior * float(r.x @ r.x))


#: Observed points (at most; evenly subsampled from the refine's) on which :func:`plain_energy` compares the
#: hypotheses: on a drill model (786 points) its E-step takes 2.2 ms at 300 points and 15 ms at 600 (measured,
#: float64, this 2-core machine). At 300, on the 122 validation drill views with a right (yaw within 15 deg) and a
#: turned-round (beyond 45 deg) hypothesis, the turned one's plain energy is at least 39 nats (median 192) above the
#: right one's (``python benchmarks/results/experiments/s45_yaw_rank/tables.py``).
PLAIN_ENERGY_POINTS = 300

#: An observed point farther than this (m) from every point of a fit's completed shape is *uncovered*
#: (:func:`uncovered_points`): about three sigma of a fitted mug or drill (sigma 2.4-3.1 mm).
UNCOVERED_RADIUS_M = 0.008


def uncovered_points(completed, observed, radius: float = UNCOVERED_RADIUS_M) -> int:
    """How many of the ``observed`` points (N, 3) lie farther than ``radius`` (m) from every point of the
    ``completed`` shape (M, 3), visible or hidden: the part of a view a fit leaves unexplained. A drill fitted
    turned round leaves its handle's and chuck's points uncovered where the right fit leaves few
    (validation drills, ``benchmarks/results/experiments/s47_coverage``)."""
    C = as_points(completed, "completed", min_points=1)
    P = as_points(observed, "observed", min_points=0)
    if len(P) == 0:
        return 0
    d, _ = cKDTree(C).query(P, distance_upper_bound=positive(radius, "radius"))
    return int(np.isinf(d).sum())


#: Two refined hypotheses closer than this in rotation (deg) and translation (m) are one mode.
SAME_MODE_DEG = 5.0
SAME_MODE_M = 5e-3


def _same_mode(a: InferenceResult, b: InferenceResult) -> bool:
    cos = (np.trace(a.R.T @ b.R) - 1.0) / 2.0
    return (math.degrees(math.acos(float(np.clip(cos, -1.0, 1.0)))) < SAME_MODE_DEG
            and float(np.linalg.norm(a.t - b.t)) < SAME_MODE_M)


def _finish(prob, st, O, w, space, residual_cpd, residual_beta, residual_lam, rank) -> InferenceResult:
    """The result of one refined state (``rank``: its place in the search's energy order): completed shape,
    visibility, optional residual CPD, confidence."""
    Y = prob.model(st.x)
    completed = st.s * Y @ st.R.T + st.t
    vis = prob.visible(completed)
    residual_W = None
    t1 = time.perf_counter()
    if residual_cpd:
        src = completed[vis]
        if len(src) >= 3:
            rb = space.beta * st.s if residual_beta is None else residual_beta
            r = nonrigid_cpd(src, O, beta=rb, lam=residual_lam, w=w, max_iter=50, tol=1e-5)
            completed = completed.copy()
            completed[vis] = r.transformed  # hidden points keep the latent completion
            residual_W = r.W
    t_residual = time.perf_counter() - t1
    conf, inlier, coverage, tau = _confidence(completed, vis, O)
    diag = {
        "inlier": inlier,
        "coverage": coverage,
        "tau": tau,
        "start_energies": [],
        "latent_norm": float(np.linalg.norm(st.x)),
        "n_visible": int(vis.sum()),
        "n_observed": int(len(O)),
        "search_rank": int(rank),
    }
    return InferenceResult(
        x=st.x.copy(),
        R=st.R.copy(),
        t=np.asarray(st.t, dtype=float).copy(),
        s=float(st.s),
        energy=float(st.energy),
        confidence=float(np.clip(conf, 0.0, 1.0)),
        completed=completed,
        sigma2=float(st.sigma2),
        iterations=int(st.iterations),
        converged=bool(st.converged),
        yaw=float(st.yaw),
        visible=vis,
        timing={"residual": t_residual},
        diagnostics=diag,
        space=space,
        residual_W=residual_W,
    )

