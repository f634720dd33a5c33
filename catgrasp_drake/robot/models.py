"""The one place that adds the project's robots (SVH hand, UR10 arm) to a MultibodyPlant.

Models live in the Drake package ``catgrasp_drake_models`` rooted at the
repository's ``models/`` folder; :func:`make_parser` is the one way to get a
:class:`~pydrake.multibody.parsing.Parser` that knows it.

Hand frame (``HAND_BASE_LINK``, identical to the vendor's ``base_link``):
origin on the wrist axis 32 mm above the hand's mounting face; **+z along the
fingers**, **+y out of the palm** (the approach direction), +x from the index
toward the little finger (the thumb sits on the -x side). See
``models/svh/README.md``.

Arm: UR10 from the standard DH parameters, base frame = DH frame 0 (z up, the
zero configuration stretches the arm along -x), flange frame ``ur10_tool0`` =
DH frame 6 (z out of the flange). See ``models/ur10/README.md``.

Mimic joints of the hand are coupler constraints, which Drake supports with
the SAP solver (``discrete_contact_approximation`` "sap", "similar" or
"lagged") or in continuous plants (kinematics, IK). Actuators are Drake PD
controlled (``JointActuator.set_controller_gains``): feed the plant's
``get_desired_state_input_port(instance)`` with ``[q_d, v_d]`` in actuator
order (= ``HAND_ACTUATED_JOINTS`` / ``ARM_JOINTS``); the PD torque is clamped
to each actuator's effort limit by the solver.
"""

from __future__ import annotations

import functools
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml
from pydrake.geometry import Cylinder, ProximityProperties
from pydrake.math import RigidTransform
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import CoulombFriction, DiscreteContactSolver, MultibodyPlant
from pydrake.multibody.tree import JointActuatorIndex, ModelInstanceIndex, PdControllerGains

from catgrasp_drake.errors import InputError, ModelFileError
from catgrasp_drake.robot.specs import (
    SVH_ACTUATED_JOINTS,
    SVH_ACTUATOR_GAINS,
    SVH_LINK_NAMES,
    UR10_ACTUATOR_GAINS,
    UR10_JOINT_NAMES,
    UR10_LINK_NAMES,
)

MODELS_DIR: Path = Path(__file__).resolve().parents[2] / "models"
PACKAGE_NAME = "catgrasp_drake_models"

ARM_URDF_URL = f"package://{PACKAGE_NAME}/ur10/ur10.urdf"
HAND_URDF_PATH: Path = MODELS_DIR / "svh" / "svh_right.urdf"
ARM_URDF_PATH: Path = MODELS_DIR / "ur10" / "ur10.urdf"
HAND_POSTURES_PATH: Path = MODELS_DIR / "svh" / "postures.yaml"

# ----------------------------------------------------------------------------- hand

#: The 9 actuated hand joints; the order of posture vectors and of the hand's actuation.
HAND_ACTUATED_JOINTS: tuple[str, ...] = SVH_ACTUATED_JOINTS
#: The 11 mimic joints (Drake coupler constraints) as {follower: (leader, multiplier, offset)}
#: are read from the URDF: see :func:`hand_mimic_joints`.
HAND_BASE_LINK = "svh_base_link"
HAND_LINKS: tuple[str, ...] = tuple(SVH_LINK_NAMES.values())
#: Distal link of each finger.
FINGER_DISTAL_LINKS: dict[str, str] = {
    "thumb": "svh_thumb_distal_link",
    "index": "svh_index_distal_link",
    "middle": "svh_middle_distal_link",
    "ring": "svh_ring_distal_link",
    "pinky": "svh_pinky_distal_link",
}
#: The link that must touch a trigger in a functional grasp.
INDEX_DISTAL_LINK = FINGER_DISTAL_LINKS["index"]
#: The index finger's actuated joints (proximal, distal): closed further to press a trigger.
INDEX_ACTUATED_JOINTS: tuple[str, ...] = ("svh_index_proximal", "svh_index_distal")
#: The thumb's actuated joints (flexion, opposition): what ``PlanParams(close_order="thumb_first")`` closes first.
THUMB_ACTUATED_JOINTS: tuple[str, ...] = ("svh_thumb_flexion", "svh_thumb_opposition")
#: Links of the thumb (any contact of these counts as "thumb contact").
THUMB_LINKS: tuple[str, ...] = (
    "svh_thumb_base_link",
    "svh_thumb_proximal_link",
    "svh_thumb_middle_link",
    "svh_thumb_distal_link",
)
#: (Kp [N m/rad], Kd [N m s/rad], effort limit [N m]) per actuated hand joint.
HAND_PD_GAINS: dict[str, tuple[float, float, float]] = dict(SVH_ACTUATOR_GAINS)

# ----------------------------------------------------------------------------- arm

ARM_JOINTS: tuple[str, ...] = UR10_JOINT_NAMES
ARM_LINKS: tuple[str, ...] = UR10_LINK_NAMES
ARM_BASE_LINK = UR10_LINK_NAMES[0]
ARM_FLANGE_FRAME = "ur10_tool0"
#: (Kp, Kd, effort limit) per arm joint.
ARM_PD_GAINS: dict[str, tuple[float, float, float]] = dict(UR10_ACTUATOR_GAINS)
#: A comfortable configuration: upper arm raised, forearm level, hand pointing down.
ARM_HOME_POSITIONS = np.array([0.0, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0.0])

#: Thickness of the adapter plate between the UR10 flange and the hand's mounting face.
HAND_ADAPTER_THICKNESS = 0.025
#: Height of the hand base frame above the hand's mounting face (vendor wrist piece).
HAND_MOUNT_OFFSET = 0.032
#: Pose of the hand base frame in the flange frame: hand +z = flange +z (fingers point out of
#: the flange), hand +y (palm normal) = flange +y, origin 25 mm (plate) + 32 mm above the flange.
X_FLANGE_HAND = RigidTransform([0.0, 0.0, HAND_ADAPTER_THICKNESS + HAND_MOUNT_OFFSET])


@dataclass(frozen=True)
class ArmHand:
    """What :func:`add_arm_and_hand` added."""

    arm: ModelInstanceIndex
    hand: ModelInstanceIndex
    hand_base_body: object  # pydrake RigidBody
    hand_base_frame: object  # pydrake Frame
    flange_frame: object  # pydrake Frame


def make_parser(plant: MultibodyPlant) -> Parser:
    """A Parser for ``plant`` with the ``catgrasp_drake_models`` package registered."""
    parser = Parser(plant)
    package_map = parser.package_map()
    if not package_map.Contains(PACKAGE_NAME):
        package_map.AddPackageXml(str(MODELS_DIR / "package.xml"))
    return parser


@functools.lru_cache(maxsize=None)
def _model_text(path: Path) -> str:
    if not path.is_file():
        raise ModelFileError(f"{path}: robot model not found (regenerate it, see models/README or the module docs)")
    return path.read_text()


def _check_mutable(plant: MultibodyPlant) -> None:
    if plant.is_finalized():
        raise InputError("the plant is already finalized; add robots before plant.Finalize()")


#: The hand URDF's declaration that a collision capsule is compliant-hydroelastic (Drake then builds its
#: tetrahedral pressure field when the model is parsed: ~85 of the hand's ~100 ms).
COMPLIANT_TAG = "<drake:compliant_hydroelastic/>"


def _parse_renamed(parser: Parser, path: Path, robot_name: str, model_name: str, *,
                   compliant: bool = True) -> ModelInstanceIndex:
    text = _model_text(path)
    if not compliant:
        if COMPLIANT_TAG not in text:
            raise ModelFileError(f"{path}: expected {COMPLIANT_TAG!r} on its collision geometry")
        text = text.replace(COMPLIANT_TAG, "")
    marker = f'<robot name="{robot_name}"'
    if marker not in text:
        raise ModelFileError(f"{path}: expected {marker!r}")
    instances = parser.AddModelsFromString(text.replace(marker, f'<robot name="{model_name}"', 1), "urdf")
    return instances[0]


def _apply_gains(plant: MultibodyPlant, instance: ModelInstanceIndex,
                 gains: dict[str, tuple[float, float, float]]) -> None:
    actuator_indices = [JointActuatorIndex(i) for i in range(plant.num_actuators())]
    for joint_name, (kp, kd, effort) in gains.items():
        joint = plant.GetJointByName(joint_name, instance)
        for index in actuator_indices:
            actuator = plant.get_mutable_joint_actuator(index)
            if actuator.joint().index() == joint.index():
                actuator.set_controller_gains(PdControllerGains(p=kp, d=kd))
                actuator.set_effort_limit(effort)
                break
        else:
            raise ModelFileError(f"joint {joint_name!r} has no actuator in the robot model")


def add_hand(plant: MultibodyPlant, parser: Parser | None = None, *, model_name: str = "svh",
             compliant: bool = True) -> ModelInstanceIndex:
    """Add the SVH hand as model instance ``model_name`` (floating unless the caller welds it).

    Its base body is ``HAND_BASE_LINK``; 9 PD-controlled actuators in
    ``HAND_ACTUATED_JOINTS`` order; 11 coupler constraints. Requires a plant
    using SAP (discrete) or a continuous plant, since the mimic joints are
    coupler constraints. ``compliant=False``: the same capsules without their
    compliant-hydroelastic pressure fields (contact by points instead) -- for
    a model that only answers distance queries, such as the planner's, which
    then parses in ~15 ms instead of ~100.
    """
    _check_mutable(plant)
    if plant.time_step() > 0 and plant.get_discrete_contact_solver() != DiscreteContactSolver.kSap:
        raise InputError(
            "the SVH hand's mimic joints need the SAP solver: use "
            'MultibodyPlantConfig(discrete_contact_approximation="sap") (or "similar"/"lagged")'
        )
    parser = parser or make_parser(plant)
    n_constraints = plant.num_constraints()
    hand = _parse_renamed(parser, HAND_URDF_PATH, "svh_right", model_name, compliant=compliant)
    added = plant.num_constraints() - n_constraints
    if added != len(hand_mimic_joints()):
        raise ModelFileError(f"expected {len(hand_mimic_joints())} coupler constraints from the hand, got {added}")
    _apply_gains(plant, hand, HAND_PD_GAINS)
    return hand


def add_arm(plant: MultibodyPlant, parser: Parser | None = None, *, model_name: str = "ur10",
            X_W_ArmBase: RigidTransform = RigidTransform()) -> ModelInstanceIndex:
    """Add the UR10 arm, its base welded to the world at ``X_W_ArmBase``."""
    _check_mutable(plant)
    parser = parser or make_parser(plant)
    arm = _parse_renamed(parser, ARM_URDF_PATH, "ur10", model_name)
    plant.WeldFrames(plant.world_frame(), plant.GetFrameByName(ARM_BASE_LINK, arm), X_W_ArmBase)
    _apply_gains(plant, arm, ARM_PD_GAINS)
    return arm


def add_arm_and_hand(plant: MultibodyPlant, parser: Parser | None = None, *,
                     X_W_ArmBase: RigidTransform = RigidTransform(), compliant_hand: bool = True) -> ArmHand:
    """Add the UR10 (welded at ``X_W_ArmBase``) with the SVH hand welded to its flange via ``X_FLANGE_HAND``.

    The adapter plate between flange and hand is added as geometry of the last
    arm link. Model instances are named "ur10" and "svh". ``compliant_hand``:
    as :func:`add_hand`'s ``compliant``.
    """
    parser = parser or make_parser(plant)
    arm = add_arm(plant, parser, X_W_ArmBase=X_W_ArmBase)
    hand = add_hand(plant, parser, compliant=compliant_hand)
    flange = plant.GetFrameByName(ARM_FLANGE_FRAME, arm)
    hand_body = plant.GetBodyByName(HAND_BASE_LINK, hand)
    _add_adapter_plate(plant, flange)
    plant.WeldFrames(flange, hand_body.body_frame(), X_FLANGE_HAND)
    return ArmHand(arm=arm, hand=hand, hand_base_body=hand_body, hand_base_frame=hand_body.body_frame(),
                   flange_frame=flange)


def _add_adapter_plate(plant: MultibodyPlant, flange) -> None:
    body = flange.body()
    X_BF = flange.GetFixedPoseInBodyFrame()
    X_BG = X_BF @ RigidTransform([0.0, 0.0, HAND_ADAPTER_THICKNESS / 2])
    shape = Cylinder(0.045, HAND_ADAPTER_THICKNESS)
    if plant.geometry_source_is_registered():
        props = ProximityProperties()
        props.AddProperty("material", "coulomb_friction", CoulombFriction(0.8, 0.6))
        plant.RegisterCollisionGeometry(body, X_BG, shape, "hand_adapter_collision", props)
        plant.RegisterVisualGeometry(body, X_BG, shape, "hand_adapter_visual", np.array([0.35, 0.36, 0.4, 1.0]))


# ----------------------------------------------------------------------------- model facts


@functools.lru_cache(maxsize=None)
def _hand_joint_table() -> dict[str, dict]:
    root = ET.fromstring(_model_text(HAND_URDF_PATH))
    table = {}
    for j in root.findall("joint"):
        lim = j.find("limit")
        mim = j.find("mimic")
        table[j.get("name")] = {
            "lower": float(lim.get("lower")),
            "upper": float(lim.get("upper")),
            "mimic": ((mim.get("joint"), float(mim.get("multiplier")), float(mim.get("offset")))
                      if mim is not None else None),
        }
    return table


def hand_joint_limits() -> dict[str, tuple[float, float]]:
    """(lower, upper) position limit of every hand joint, from the hand URDF."""
    return {name: (row["lower"], row["upper"]) for name, row in _hand_joint_table().items()}


def hand_mimic_joints() -> dict[str, tuple[str, float, float]]:
    """{follower joint: (leader joint, multiplier, offset)} of the 11 mimic joints (follower = m·leader + offset)."""
    return {name: row["mimic"] for name, row in _hand_joint_table().items() if row["mimic"] is not None}


def hand_joint_angles(q_hand: np.ndarray) -> dict[str, float]:
    """All hand joint angles (actuated + mimic followers) for a 9-vector posture (``HAND_ACTUATED_JOINTS`` order).

    The one place the mimic relation (follower = multiplier * leader + offset) is resolved.
    """
    angles = {name: float(q) for name, q in zip(HAND_ACTUATED_JOINTS, q_hand)}
    mimic = hand_mimic_joints()
    for _ in range(len(mimic)):  # followers of followers resolve in a few passes
        for follower, (leader, multiplier, offset) in mimic.items():
            if leader in angles:
                angles[follower] = multiplier * angles[leader] + offset
    return angles


def set_hand_angles(plant: MultibodyPlant, context, hand: ModelInstanceIndex, q_hand: np.ndarray) -> None:
    """Set every hand joint (actuated + mimic followers) in ``context`` for the posture ``q_hand``."""
    for name, q in hand_joint_angles(q_hand).items():
        plant.GetJointByName(name, hand).set_angle(context, q)


def set_hand_default_posture(plant: MultibodyPlant, hand: ModelInstanceIndex, q_hand: np.ndarray) -> None:
    """Default angles of all hand joints for the posture ``q_hand`` (HAND_ACTUATED_JOINTS order)."""
    for name, q in hand_joint_angles(q_hand).items():
        plant.GetJointByName(name, hand).set_default_angle(q)


def hand_links() -> tuple[str, ...]:
    """Names of all hand bodies (same as ``HAND_LINKS``)."""
    return HAND_LINKS


# ----------------------------------------------------------------------------- postures


@functools.lru_cache(maxsize=None)
def _postures_file() -> dict:
    if not HAND_POSTURES_PATH.is_file():
        raise ModelFileError(f"{HAND_POSTURES_PATH}: hand posture file not found")
    try:
        data = yaml.safe_load(HAND_POSTURES_PATH.read_text())
    except yaml.YAMLError as exc:
        raise ModelFileError(f"{HAND_POSTURES_PATH}: not valid YAML ({exc})") from exc
    if not isinstance(data, dict) or not isinstance(data.get("categories"), dict):
        raise ModelFileError(f"{HAND_POSTURES_PATH}: expected a mapping with key 'categories'")
    return data


def hand_posture_categories() -> tuple[str, ...]:
    """Categories that have hand postures."""
    return tuple(_postures_file()["categories"])


def load_hand_postures(category: str) -> dict[str, np.ndarray]:
    """Hand postures of ``category`` ({name: 9-vector in ``HAND_ACTUATED_JOINTS`` order}, radians).

    Every category has at least "open", "preshape" and "closed". "closed" may
    aim beyond contact: the effort-limited PD actuators then squeeze with
    their effort limits.
    """
    categories = _postures_file()["categories"]
    if not isinstance(category, str) or category not in categories:
        raise InputError(f"unknown hand posture category {category!r}; known: {', '.join(sorted(categories))}")
    limits = hand_joint_limits()
    postures = {}
    for name, by_joint in categories[category].items():
        if not isinstance(by_joint, dict):
            raise ModelFileError(f"{HAND_POSTURES_PATH}: {category}.{name} must map joint names to angles")
        unknown = set(by_joint) - set(HAND_ACTUATED_JOINTS)
        missing = [j for j in HAND_ACTUATED_JOINTS if j not in by_joint]
        if unknown or missing:
            raise ModelFileError(
                f"{HAND_POSTURES_PATH}: {category}.{name}: unknown joints {sorted(unknown)}, missing {missing}"
            )
        q = np.array([float(by_joint[j]) for j in HAND_ACTUATED_JOINTS])
        for j, value in zip(HAND_ACTUATED_JOINTS, q):
            lo, hi = limits[j]
            if not (lo - 1e-9 <= value <= hi + 1e-9):
                raise ModelFileError(
                    f"{HAND_POSTURES_PATH}: {category}.{name}.{j} = {value} outside the joint limits [{lo}, {hi}]"
                )
        postures[name] = q
    for required in ("open", "preshape", "closed"):
        if required not in postures:
            raise ModelFileError(f"{HAND_POSTURES_PATH}: category {category!r} lacks the posture {required!r}")
    return postures
