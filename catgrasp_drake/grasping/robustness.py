"""How robust a grasp is: seeded perturbations of a trial and the score of its outcome (pure numpy).

A grasp's *robustness* is the mean score over trials, each executed under a
seeded perturbation of what the grasp was planned for --

- the object's pose off by up to ``shift_m`` (uniform in a disc, m) and
  ``turn_deg`` (about the vertical through the object's origin, deg);
- optionally its height off by up to ``height_m`` (uniform, m): the grasp lands that much higher or lower
  on the object, as a perception error in height would put it (0, the default: never, as before -- the
  table holds the object, so the pose above has no vertical part; a drill grasp's best height was found to
  be a few millimetres wide on heavy drills, session 27);
- the object's friction drawn from ``friction`` (uniform);
- its mass times a factor drawn from ``mass_scale`` (uniform),

and each trial scores ``1`` for a functional grasp, ``grasp_weight`` for a
grasp that holds but misses the function, ``0`` else. Perturbation 0 of every
instance is the nominal one. Used by the grasp search
(``catgrasp_drake.grasp_search``) and by training's per-instance search
(``catgrasp_drake.training``); the trial itself is
:func:`catgrasp_drake.trial.run_perturbed_trial`.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from catgrasp_drake.errors import InputError


@dataclass(frozen=True)
class Robustness:
    """How a candidate grasp is scored (module docstring). SI units; angles in degrees."""

    perturbations: int = 2  # per instance (the first is the nominal placement)
    shift_m: float = 0.01
    turn_deg: float = 5.0
    height_m: float = 0.0
    friction: tuple[float, float] = (0.5, 1.0)
    mass_scale: tuple[float, float] = (0.7, 1.3)
    grasp_weight: float = 0.2
    seed: int = 0

    def __post_init__(self):
        if not (isinstance(self.perturbations, int) and self.perturbations >= 1):
            raise InputError(f"perturbations: expected a positive integer, got {self.perturbations!r}")
        for name in ("friction", "mass_scale"):
            lo, hi = getattr(self, name)
            if not 0 < lo <= hi:
                raise InputError(f"{name}: expected 0 < low <= high, got {(lo, hi)}")
        if self.shift_m < 0 or self.turn_deg < 0 or not 0 <= self.grasp_weight <= 1:
            raise InputError("shift_m, turn_deg >= 0 and grasp_weight in [0, 1] expected")
        if not (isinstance(self.height_m, (int, float)) and 0 <= self.height_m <= 0.05):
            raise InputError(f"height_m: expected 0 to 0.05 m (a grasp's height error), got {self.height_m!r}")


def perturbation(robustness: Robustness, instance: str, k: int) -> dict:
    """The ``k``-th perturbation of ``instance`` (k = 0: nominal): a JSON-able dict, seeded by (seed, instance, k).

    Keys: ``dx``, ``dy`` (m, object frame), ``dyaw_deg``, ``friction`` (None: the scenario's own) and
    ``mass_scale``; with ``height_m > 0`` also ``dz`` (m, object frame; drawn after the others, which keep
    the values they have without it).
    """
    if k == 0:
        nominal = {"dx": 0.0, "dy": 0.0, "dyaw_deg": 0.0, "friction": None, "mass_scale": 1.0}
        return nominal | ({"dz": 0.0} if robustness.height_m > 0 else {})
    rng = np.random.default_rng([robustness.seed, zlib.crc32(instance.encode()), k, 18])
    r = robustness.shift_m * math.sqrt(rng.uniform())
    a = rng.uniform(0, 2 * math.pi)
    p = {"dx": round(r * math.cos(a), 6), "dy": round(r * math.sin(a), 6),
         "dyaw_deg": round(float(rng.uniform(-robustness.turn_deg, robustness.turn_deg)), 4),
         "friction": round(float(rng.uniform(*robustness.friction)), 4),
         "mass_scale": round(float(rng.uniform(*robustness.mass_scale)), 4)}
    if robustness.height_m > 0:
        p["dz"] = round(float(rng.uniform(-robustness.height_m, robustness.height_m)), 6)
    return p


def object_offset(p: dict) -> np.ndarray:
    """The 4x4 pose E (in the object frame O) by which perturbation ``p`` moves the object off its plan.

    A grasp planned in O is executed on the moved object by moving its poses by ``E^-1``.
    """
    E = np.eye(4)
    E[:3, :3] = Rotation.from_euler("z", p["dyaw_deg"], degrees=True).as_matrix()
    E[:3, 3] = (p["dx"], p["dy"], p.get("dz", 0.0))
    return E


def trial_score(outcome: dict, grasp_weight: float) -> float:
    """1 for a functional grasp, ``grasp_weight`` for a held one, 0 else."""
    return 1.0 if outcome.get("functional") else grasp_weight if outcome.get("grasp") else 0.0
