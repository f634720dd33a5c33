"""Hand-written grasp motions stored as YAML (``models/grasps/<category>_handwritten.yaml``).

The poses are written the way one describes a grasp: where the hand base link
H sits relative to an annotated feature of the instance and where its fingers
and palm point, all in the object frame O::

    category: drill
    anchor: {region: trigger, point: [0.0, 0.0, 0.0]}  # offset added to the region centre (m, O)
    grasp:
      position: [0.045, -0.10, -0.01]   # H origin relative to the anchor (m, O)
      fingers: [0, 1, 0]                # H's +z (along the fingers) in O
      palm: [-1, 0, 0]                  # H's +y (out of the palm) in O
    pregrasp_distance: 0.08             # pregrasp = grasp moved back by this along -palm
    postures: drill                     # hand posture set (models/svh/postures.yaml)
    posture_overrides: {closed: {svh_index_distal: 1.2}}  # optional, per joint (rad)
    lift_height: 0.12
    hold_time: 2.0

``fingers`` and ``palm`` need not be exactly orthogonal: the palm direction
is orthogonalised against the fingers. The anchor makes one file fit every
instance of the category (the trigger moves from drill to drill).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import yaml

from catgrasp_drake.data.dataset import imported_object, load_annotations, read_annotations
from catgrasp_drake.errors import InputError, ModelFileError
from catgrasp_drake.grasping.constraints import load_constraint
from catgrasp_drake.grasping.motion import GraspMotion
from catgrasp_drake.grasping.sampling import perturb_poses
from catgrasp_drake.robot.models import HAND_ACTUATED_JOINTS, hand_joint_limits, load_hand_postures
from catgrasp_drake.station.scenario import load_scenario, random_placement, with_instance

GRASPS_DIR = Path(__file__).resolve().parents[2] / "models" / "grasps"
#: Tolerance (rad) of the joint-limit check of posture overrides: searched grasps are written rounded to 1e-4 rad.
LIMIT_TOL = 1e-4
_FIELDS = {"category", "anchor", "grasp", "pregrasp_distance", "postures", "posture_overrides",
           "lift_height", "hold_time", "description"}


def hand_rotation(fingers, palm) -> np.ndarray:
    """R_OH with H's +z along ``fingers`` and +y along ``palm`` (orthogonalised), x = y × z."""
    z = np.asarray(fingers, float)
    y = np.asarray(palm, float)
    if z.shape != (3,) or y.shape != (3,) or np.linalg.norm(z) < 1e-9:
        raise InputError(f"fingers/palm: expected two 3-vectors, got {fingers!r}, {palm!r}")
    z = z / np.linalg.norm(z)
    y = y - (y @ z) * z
    if np.linalg.norm(y) < 1e-6:
        raise InputError("fingers and palm directions are parallel")
    y /= np.linalg.norm(y)
    return np.column_stack([np.cross(y, z), y, z])


def motion_from_spec(spec: dict, annotations: dict | None = None, postures: dict | None = None,
                     where: str = "grasp") -> GraspMotion:
    """A ``GraspMotion`` (object frame) from one parsed hand-written spec (module docstring)."""
    if not isinstance(spec, dict):
        raise InputError(f"{where}: expected a mapping")
    unknown = sorted(set(spec) - _FIELDS)
    if unknown:
        raise InputError(f"{where}: unknown field(s) {unknown}; known: {sorted(_FIELDS)}")
    anchor = np.zeros(3)
    a = spec.get("anchor") or {}
    if "region" in a:
        regions = (annotations or {}).get("regions", {})
        if a["region"] not in regions:
            raise InputError(f"{where}.anchor: region {a['region']!r} not annotated; have {sorted(regions)}")
        anchor = np.asarray(regions[a["region"]]["center"], float)
    anchor = anchor + np.asarray(a.get("point", (0.0, 0.0, 0.0)), float)
    g = spec.get("grasp")
    if not isinstance(g, dict) or not {"position", "fingers", "palm"} <= set(g):
        raise InputError(f"{where}.grasp: needs position, fingers and palm")
    R = hand_rotation(g["fingers"], g["palm"])
    X_grasp = np.eye(4)
    X_grasp[:3, :3] = R
    X_grasp[:3, 3] = anchor + np.asarray(g["position"], float)
    X_pre = X_grasp.copy()
    X_pre[:3, 3] -= float(spec.get("pregrasp_distance", 0.08)) * R[:, 1]
    if postures is None:
        postures = load_hand_postures(spec.get("postures", spec.get("category")))
    postures = overridden_postures(postures, spec.get("posture_overrides") or {}, f"{where}.posture_overrides")
    return GraspMotion(np.stack([X_pre, X_grasp]), ("pregrasp", "grasp"), postures, "object",
                       float(spec.get("lift_height", 0.12)), float(spec.get("hold_time", 2.0)))


def overridden_postures(postures, overrides, where: str = "posture_overrides") -> dict[str, np.ndarray]:
    """``postures`` (name -> 9 joint angles, rad) with ``overrides`` ({posture: {joint: angle (rad)}}) written in.

    Unknown postures or joints, and angles that are not numbers or outside the joint's limits, raise
    ``InputError`` naming them."""
    if not isinstance(overrides, dict):
        raise InputError(f"{where}: expected a mapping posture -> {{joint: angle}}")
    postures = {k: np.array(v, float) for k, v in postures.items()}
    limits = hand_joint_limits()
    for name, joints in overrides.items():
        if name not in postures:
            raise InputError(f"{where}: unknown posture {name!r}; have {sorted(postures)}")
        if not isinstance(joints, dict):
            raise InputError(f"{where}.{name}: expected a mapping joint -> angle (rad)")
        for joint, value in joints.items():
            if joint not in HAND_ACTUATED_JOINTS:
                raise InputError(f"{where}.{name}: unknown joint {joint!r}; joints: {', '.join(HAND_ACTUATED_JOINTS)}")
            try:
                angle = float(value)
            except (TypeError, ValueError):
                angle = float("nan")
            if not np.isfinite(angle):
                raise InputError(f"{where}.{name}.{joint}: expected an angle in radians, got {value!r}")
            lo, hi = limits[joint]
            if not lo - LIMIT_TOL <= angle <= hi + LIMIT_TOL:
                raise InputError(f"{where}.{name}.{joint} = {angle} rad: outside the joint limits [{lo}, {hi}]")
            postures[name][HAND_ACTUATED_JOINTS.index(joint)] = angle
    return postures


def with_postures(motion: GraspMotion, overrides) -> GraspMotion:
    """``motion`` with some joints of its postures replaced: ``overrides`` = {posture: {joint: angle (rad)}},
    e.g. ``{"closed": {"svh_pinky": 0.856}}`` -- the way to try a posture change on a grasp."""
    return replace(motion, postures=overridden_postures(motion.postures, overrides))


def _annotations(category: str, instance: str, annotations_dir: str | Path | None) -> dict:
    if annotations_dir is None:
        return load_annotations(category, instance)
    return read_annotations(Path(annotations_dir) / "annotations.json")


def load_handwritten_motion(category: str, instance: str, path: str | Path | None = None, *,
                            annotations_dir: str | Path | None = None) -> GraspMotion:
    """The hand-written grasp of ``category`` fitted to ``instance``'s annotations (object frame).

    ``annotations_dir``: an imported object's directory (its ``annotations.json``) instead of the
    embedded data set's instance."""
    path = Path(path) if path is not None else GRASPS_DIR / f"{category}_handwritten.yaml"
    spec = read_grasp_file(path, category)
    return motion_from_spec(spec, _annotations(category, instance, annotations_dir), where=str(path.name))


def read_grasp_file(path: str | Path, category: str | None = None):
    """The parsed grasp file at ``path`` (a hand-written or searched grasp; the format in the module docstring).

    ModelFileError if it cannot be read, InputError if it is not YAML or names another category than
    ``category`` (when given; a file without ``category`` fits any). The fields are checked when a motion is
    made from it (:func:`motion_from_spec`)."""
    path = Path(path)
    try:
        spec = yaml.safe_load(path.read_text())
    except OSError as e:
        raise ModelFileError(f"{path}: cannot read hand-written grasp ({e})") from None
    except yaml.YAMLError as e:
        raise InputError(f"{path}: not valid YAML ({e})") from None
    if category is not None and isinstance(spec, dict) and spec.get("category", category) != category:
        raise InputError(f"{path}: grasp for {spec.get('category')!r}, not {category!r}")
    return spec


def shifted_motion(motion: GraspMotion, category: str, instance: str, shift_O, rotate_deg=(0.0, 0.0, 0.0), *,
                   annotations_dir: str | Path | None = None) -> GraspMotion:
    """``motion`` (object frame) turned by x-y-z Euler angles ``rotate_deg`` (deg) about the centre of the
    category's functional region on ``instance`` (the trigger or handle), then moved by ``shift_O`` (m, O)."""
    region = load_constraint(category).region
    pivot = _annotations(category, instance, annotations_dir)["regions"][region]["center"]
    return moved_about(motion, pivot, shift_O, rotate_deg)


def moved_about(motion: GraspMotion, pivot_O, shift_O, rotate_deg=(0.0, 0.0, 0.0)) -> GraspMotion:
    """``motion`` (object frame) turned by x-y-z Euler angles ``rotate_deg`` (deg) about ``pivot_O`` (m, O),
    then moved by ``shift_O`` (m, O)."""
    from scipy.spatial.transform import Rotation

    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("xyz", rotate_deg, degrees=True).as_matrix()
    T[:3, 3] = np.asarray(shift_O, float)
    return replace(motion, poses=perturb_poses(motion.poses, T, np.asarray(pivot_O, float)))


def handwritten_trial(category: str | None = None, instance: str | None = None, *, object_dir=None,
                      seed: int | None = None, shift_O=None, grasp_file: str | Path | None = None):
    """The scenario and the hand-written grasp (object frame) of one trial: ``(Scenario, GraspMotion)``.

    The object is the embedded ``instance`` of ``category`` (None: the category's default scenario's), or
    the imported object in ``object_dir`` (``catgrasp import-object``; its category, which ``category`` must
    match when given); placed by ``seed`` (:func:`~catgrasp_drake.station.scenario.random_placement`; None:
    the scenario's pose); the grasp moved by ``shift_O`` (m, O; :func:`shifted_motion`); ``grasp_file``: a grasp
    file to run instead of the category's (``models/grasps/<category>_handwritten.yaml``; e.g. a searched one).
    What ``catgrasp film`` and ``diagrams/trace_trial.py`` run."""
    if object_dir is not None:
        obj_category, instance = imported_object(object_dir)
        if category not in (None, obj_category):
            raise InputError(f"category {category!r}: {object_dir} holds a {obj_category}")
        category = obj_category
    elif category is None:
        raise InputError("give a category (and an instance) or an imported object's directory")
    scenario = load_scenario(f"{category}_default")
    if instance is not None:
        scenario = with_instance(scenario, instance, category=category, model_dir=object_dir)
    if seed is not None:
        scenario = random_placement(scenario, seed)
    instance = scenario.object.instance
    motion = load_handwritten_motion(category, instance, grasp_file, annotations_dir=object_dir)
    if shift_O is not None:
        motion = shifted_motion(motion, category, instance, shift_O, annotations_dir=object_dir)
    return scenario, motion
