"""Station scenarios: a typed ``Scenario`` record loaded from YAML with named entries.

Style of Drake's ``examples/hardware_sim`` and the manipulation course's
``station.py``: every field has a default, a YAML entry only states what
differs, and one builder (:mod:`catgrasp_drake.station.builder`) turns a
``Scenario`` into a diagram.

Frames and units (SI throughout, angles in DEGREES in the YAML and here,
``*_deg`` fields; Drake's extrinsic roll-pitch-yaw convention):

- ``W`` world: z up; the arm base sits at ``arm_base`` (default the origin).
- ``T`` table top: the centre of the table's top surface, z up; the table box
  hangs below it (``table.size`` = full x, y, z extents).
- ``O`` object: the instance's canonical frame (z up, base on z = 0,
  functional direction +y); placed on the table by ``object.xyz`` (in T) and
  ``object.yaw_deg`` (about T's z): ``X_WO = X_WT * X_TO``.
- ``C`` camera: Drake's camera convention (z forward, x right, y down),
  given either as ``X_WC: {xyz, rpy_deg}`` or as ``look_at: {eye, target}``
  in the world frame.

YAML format (a mapping ``name -> scenario``; omitted fields take the defaults
below)::

    drill_default:
      object: {category: drill, instance: drill_00, xyz: [0.0, 0.0, 0.0], yaw_deg: 0.0}
      arm_base: {xyz: [0, 0, 0], rpy_deg: [0, 0, 0]}
      arm_q_home: [...]                # 6 joint angles, radians
      table: {xyz: [0.55, 0, 0], rpy_deg: [0, 0, 0], size: [1.2, 1.4, 0.05]}
      cameras:
        - {name: camera0, look_at: {eye: [...], target: [...]},
           width: 640, height: 480, fov_y_deg: 45, depth_range: [0.1, 3.0]}
      object_cloud: {voxel_size: 0.005, crop_min: [...], crop_max: [...],
                     depth_noise_std: 0.0, seed: 0}
      plant: {time_step: 0.005, discrete_contact_approximation: sap,
              contact_model: hydroelastic_with_fallback}
      meshcat: false

    cylinder_test:
      object: {primitive: {shape: cylinder, radius: 0.02, length: 0.15, mass_kg: 0.2},
               xyz: [0.1, 0.0, 0.0]}
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from catgrasp_drake.core.visibility import look_at_matrix
from catgrasp_drake.data.dataset import CATEGORIES, list_instances, load_annotations, read_annotations
from catgrasp_drake.errors import InputError, ModelFileError

#: The project's scenario file.
DEFAULT_SCENARIO_FILE = Path(__file__).resolve().parents[2] / "models" / "station.scenarios.yaml"


# ----------------------------------------------------------------------------- records
@dataclass(frozen=True)
class Pose:
    """A rigid transform as translation (m) + extrinsic roll-pitch-yaw (degrees)."""

    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy_deg: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def matrix(self) -> np.ndarray:
        """The 4x4 homogeneous transform."""
        r, p, y = np.radians(self.rpy_deg)
        cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
        R = np.array([
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ])
        X = np.eye(4)
        X[:3, :3] = R
        X[:3, 3] = self.xyz
        return X


@dataclass(frozen=True)
class PrimitiveObject:
    """A primitive test object (model name ``cylinder``/``box``, one link ``body``, base on z = 0)."""

    shape: str = "cylinder"  # "cylinder" (radius, length) or "box" (size)
    radius: float = 0.02
    length: float = 0.15
    size: tuple[float, float, float] = (0.05, 0.05, 0.15)
    mass_kg: float = 0.2
    friction: float = 0.9


@dataclass(frozen=True)
class ObjectSpec:
    """The object to grasp: a data-set instance (category + instance) or a primitive."""

    category: str | None = "drill"
    instance: str | None = "drill_00"
    primitive: PrimitiveObject | None = None
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)  # in the table-top frame T
    yaw_deg: float = 0.0  # about T's z
    #: A folder holding ``<instance>.sdf`` and ``annotations.json`` (e.g. a prepared YCB object,
    #: ``out/ycb/drill/ycb_035``) instead of the embedded data set.
    model_dir: str | None = None

    def sdf_file(self) -> str | None:
        """The SDF file of an object given by ``model_dir`` (None for data-set instances and primitives)."""
        return None if self.model_dir is None else str(Path(self.model_dir) / f"{self.instance}.sdf")

    def annotations(self) -> dict:
        """The object's annotations (functional regions in its canonical frame); {} for primitives."""
        if self.model_dir is not None:
            return read_annotations(Path(self.model_dir) / "annotations.json")
        if self.category is None:
            return {}
        return load_annotations(self.category, self.instance)

    @property
    def model_name(self) -> str:
        return self.primitive.shape if self.primitive is not None else str(self.instance)

    def X_TO(self) -> np.ndarray:
        return Pose(self.xyz, (0.0, 0.0, self.yaw_deg)).matrix()


@dataclass(frozen=True)
class TableSpec:
    """A box table; ``pose`` is the centre of its TOP surface (frame T)."""

    pose: Pose = Pose((0.55, 0.0, 0.0))
    size: tuple[float, float, float] = (1.2, 1.4, 0.05)
    friction: float = 0.6
    hydroelastic_modulus: float = 1e7


@dataclass(frozen=True)
class CameraSpec:
    """A fixed depth camera (RgbdSensor with RenderEngineVtk)."""

    name: str = "camera0"
    X_WC: Pose | None = None
    look_at_eye: tuple[float, float, float] | None = (1.15, -0.45, 0.55)
    look_at_target: tuple[float, float, float] | None = (0.55, 0.0, 0.08)
    width: int = 640
    height: int = 480
    fov_y_deg: float = 45.0
    depth_range: tuple[float, float] = (0.1, 3.0)

    def X_WC_matrix(self) -> np.ndarray:
        if self.X_WC is not None:
            return self.X_WC.matrix()
        return look_at_matrix(self.look_at_eye, self.look_at_target)


@dataclass(frozen=True)
class ObjectCloudSpec:
    """Post-processing of the segmented camera cloud (world frame, metres)."""

    voxel_size: float = 0.005
    crop_min: tuple[float, float, float] = (-0.5, -1.0, -0.02)
    crop_max: tuple[float, float, float] = (1.5, 1.0, 1.0)
    depth_noise_std: float = 0.0  # m; "kinect": the axial std at 1 m (it grows with depth squared)
    seed: int = 0
    depth_noise_model: str = "gaussian"  # or "kinect" (perception.object_cloud._mask_depth)
    edge_dropout: float = 0.0  # "kinect": probability of dropping a silhouette / depth-jump pixel


@dataclass(frozen=True)
class PlantSpec:
    """MultibodyPlantConfig fields the station sets."""

    time_step: float = 5e-3
    discrete_contact_approximation: str = "sap"
    contact_model: str = "hydroelastic_with_fallback"
    penetration_allowance: float = 1e-3
    #: Physics-sensitivity knobs (defaults: the station as tuned): the hand's effort limits times
    #: this factor (1/1.7: the real SVH's), and the object's Coulomb friction replaced (None: its SDF's).
    hand_effort_scale: float = 1.0
    object_friction: float | None = None
    #: Speed lever (issue 17): the hand's compliant-hydroelastic mesh resolution hint (m) replaced
    #: (None: the model's 6 mm); coarser tessellations mean fewer contact polygons for SAP.
    hand_resolution_hint: float | None = None
    #: Robustness knob (grasp search): the object's mass (and with it its rotational inertia) times
    #: this factor, applied to the simulation context (``station.builder.apply_context_knobs``).
    object_mass_scale: float = 1.0


#: UR10 home configuration (rad): the robot model's home turned by pi about the base so the
#: hand is above the table (+x), fingers down.
DEFAULT_ARM_Q_HOME = (math.pi, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0.0)


@dataclass(frozen=True)
class Scenario:
    """Everything the station builder needs; see the module docstring for frames and YAML."""

    name: str = "unnamed"
    object: ObjectSpec = ObjectSpec()
    arm_base: Pose = Pose()
    arm_q_home: tuple[float, ...] = DEFAULT_ARM_Q_HOME
    table: TableSpec = TableSpec()
    cameras: tuple[CameraSpec, ...] = (CameraSpec(),)
    object_cloud: ObjectCloudSpec = ObjectCloudSpec()
    plant: PlantSpec = PlantSpec()
    meshcat: bool = False

    def X_WO(self) -> np.ndarray:
        """Initial pose of the object in the world (4x4)."""
        return self.table.pose.matrix() @ self.object.X_TO()

    def replace(self, **changes) -> "Scenario":
        return dataclasses.replace(self, **changes)


# ----------------------------------------------------------------------------- parsing
def _vec(value, n: int, where: str) -> tuple[float, ...]:
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{where}: expected {n} numbers, got {value!r}") from None
    if a.shape != (n,) or not np.all(np.isfinite(a)):
        raise InputError(f"{where}: expected {n} finite numbers, got {value!r}")
    return tuple(float(v) for v in a)


def _num(value, where: str, *, positive: bool = False, nonneg: bool = False) -> float:
    if isinstance(value, bool):
        raise InputError(f"{where}: expected a number, got {value!r}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{where}: expected a number, got {value!r}") from None
    if not math.isfinite(v) or (positive and v <= 0) or (nonneg and v < 0):
        kind = "positive " if positive else "non-negative " if nonneg else "finite "
        raise InputError(f"{where}: expected a {kind}number, got {value!r}")
    return v


def _mapping(value, where: str, allowed: set[str]) -> dict:
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise InputError(f"{where}: expected a mapping, got {type(value).__name__}")
    unknown = sorted(set(value) - allowed)
    if unknown:
        raise InputError(f"{where}: unknown field(s) {', '.join(map(repr, unknown))}; "
                         f"known: {', '.join(sorted(allowed))}")
    return value


def _pose(value, where: str, default: Pose = Pose()) -> Pose:
    d = _mapping(value, where, {"xyz", "rpy_deg"})
    return Pose(_vec(d.get("xyz", default.xyz), 3, f"{where}.xyz"),
                _vec(d.get("rpy_deg", default.rpy_deg), 3, f"{where}.rpy_deg"))


def _primitive(value, where: str) -> PrimitiveObject:
    d = _mapping(value, where, {f.name for f in dataclasses.fields(PrimitiveObject)})
    p = PrimitiveObject()
    shape = d.get("shape", p.shape)
    if shape not in ("cylinder", "box"):
        raise InputError(f"{where}.shape: expected 'cylinder' or 'box', got {shape!r}")
    return PrimitiveObject(
        shape=shape,
        radius=_num(d.get("radius", p.radius), f"{where}.radius", positive=True),
        length=_num(d.get("length", p.length), f"{where}.length", positive=True),
        size=_vec(d.get("size", p.size), 3, f"{where}.size"),
        mass_kg=_num(d.get("mass_kg", p.mass_kg), f"{where}.mass_kg", positive=True),
        friction=_num(d.get("friction", p.friction), f"{where}.friction", positive=True),
    )


def _object(value, where: str) -> ObjectSpec:
    d = _mapping(value, where, {"category", "instance", "primitive", "xyz", "yaw_deg", "model_dir"})
    xyz = _vec(d.get("xyz", (0.0, 0.0, 0.0)), 3, f"{where}.xyz")
    yaw = _num(d.get("yaw_deg", 0.0), f"{where}.yaw_deg")
    if "primitive" in d:
        if "category" in d or "instance" in d:
            raise InputError(f"{where}: give either primitive or category + instance, not both")
        return ObjectSpec(None, None, _primitive(d["primitive"], f"{where}.primitive"), xyz, yaw)
    category = d.get("category", ObjectSpec.category)
    instance = d.get("instance", f"{category}_00")
    if category not in CATEGORIES:
        raise InputError(f"{where}.category: unknown category {category!r}; known: {', '.join(CATEGORIES)}")
    if "model_dir" in d:
        model_dir = str(d["model_dir"])
        if not (Path(model_dir) / f"{instance}.sdf").is_file():
            raise InputError(f"{where}.model_dir: no {instance}.sdf in {model_dir}")
        return ObjectSpec(category, instance, None, xyz, yaw, model_dir)
    if instance not in list_instances(category):
        raise InputError(f"{where}.instance: unknown instance {instance!r} of {category!r}")
    return ObjectSpec(category, instance, None, xyz, yaw)


def _camera(value, where: str) -> CameraSpec:
    d = _mapping(value, where, {"name", "X_WC", "look_at", "width", "height", "fov_y_deg", "depth_range"})
    c = CameraSpec()
    X_WC, eye, target = None, c.look_at_eye, c.look_at_target
    if "X_WC" in d and "look_at" in d:
        raise InputError(f"{where}: give either X_WC or look_at, not both")
    if "X_WC" in d:
        X_WC, eye, target = _pose(d["X_WC"], f"{where}.X_WC"), None, None
    elif "look_at" in d:
        la = _mapping(d["look_at"], f"{where}.look_at", {"eye", "target"})
        eye = _vec(la.get("eye", eye), 3, f"{where}.look_at.eye")
        target = _vec(la.get("target", target), 3, f"{where}.look_at.target")
        if np.allclose(eye, target):
            raise InputError(f"{where}.look_at: eye and target coincide")
    depth_range = _vec(d.get("depth_range", c.depth_range), 2, f"{where}.depth_range")
    if not 0 < depth_range[0] < depth_range[1]:
        raise InputError(f"{where}.depth_range: expected 0 < near < far, got {list(depth_range)}")
    fov = _num(d.get("fov_y_deg", c.fov_y_deg), f"{where}.fov_y_deg", positive=True)
    if fov >= 180:
        raise InputError(f"{where}.fov_y_deg: expected < 180, got {fov}")
    width, height = d.get("width", c.width), d.get("height", c.height)
    for k, v in (("width", width), ("height", height)):
        if not isinstance(v, int) or isinstance(v, bool) or v <= 0:
            raise InputError(f"{where}.{k}: expected a positive integer, got {v!r}")
    name = d.get("name", c.name)
    if not isinstance(name, str) or not name.isidentifier():
        raise InputError(f"{where}.name: expected an identifier-like name, got {name!r}")
    return CameraSpec(name, X_WC, eye, target, width, height, fov, depth_range)


def _object_cloud(value, where: str) -> ObjectCloudSpec:
    d = _mapping(value, where, {f.name for f in dataclasses.fields(ObjectCloudSpec)})
    c = ObjectCloudSpec()
    lo = _vec(d.get("crop_min", c.crop_min), 3, f"{where}.crop_min")
    hi = _vec(d.get("crop_max", c.crop_max), 3, f"{where}.crop_max")
    if not all(a < b for a, b in zip(lo, hi)):
        raise InputError(f"{where}: crop_min must be below crop_max in every axis")
    seed = d.get("seed", c.seed)
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        raise InputError(f"{where}.seed: expected a non-negative integer, got {seed!r}")
    model = d.get("depth_noise_model", c.depth_noise_model)
    if model not in ("gaussian", "kinect"):
        raise InputError(f"{where}.depth_noise_model: expected 'gaussian' or 'kinect', got {model!r}")
    dropout = _num(d.get("edge_dropout", c.edge_dropout), f"{where}.edge_dropout", nonneg=True)
    if dropout > 1.0:
        raise InputError(f"{where}.edge_dropout: a probability in [0, 1], got {dropout:g}")
    return ObjectCloudSpec(
        voxel_size=_num(d.get("voxel_size", c.voxel_size), f"{where}.voxel_size", nonneg=True),
        crop_min=lo, crop_max=hi,
        depth_noise_std=_num(d.get("depth_noise_std", c.depth_noise_std), f"{where}.depth_noise_std", nonneg=True),
        seed=seed, depth_noise_model=model, edge_dropout=dropout,
    )


_APPROXIMATIONS = ("sap", "tamsi", "similar", "lagged", "")
_CONTACT_MODELS = ("hydroelastic_with_fallback", "hydroelastic", "point")


def _plant(value, where: str) -> PlantSpec:
    d = _mapping(value, where, {f.name for f in dataclasses.fields(PlantSpec)})
    p = PlantSpec()
    approx = d.get("discrete_contact_approximation", p.discrete_contact_approximation)
    if approx not in _APPROXIMATIONS:
        raise InputError(f"{where}.discrete_contact_approximation: expected one of {_APPROXIMATIONS}, got {approx!r}")
    model = d.get("contact_model", p.contact_model)
    if model not in _CONTACT_MODELS:
        raise InputError(f"{where}.contact_model: expected one of {_CONTACT_MODELS}, got {model!r}")
    return PlantSpec(
        time_step=_num(d.get("time_step", p.time_step), f"{where}.time_step", positive=True),
        discrete_contact_approximation=approx,
        contact_model=model,
        penetration_allowance=_num(d.get("penetration_allowance", p.penetration_allowance),
                                   f"{where}.penetration_allowance", positive=True),
        hand_effort_scale=_num(d.get("hand_effort_scale", p.hand_effort_scale), f"{where}.hand_effort_scale",
                               positive=True),
        object_friction=None if d.get("object_friction") is None else _num(
            d["object_friction"], f"{where}.object_friction", positive=True),
        hand_resolution_hint=None if d.get("hand_resolution_hint") is None else _num(
            d["hand_resolution_hint"], f"{where}.hand_resolution_hint", positive=True),
        object_mass_scale=_num(d.get("object_mass_scale", p.object_mass_scale), f"{where}.object_mass_scale",
                               positive=True),
    )


def _table(value, where: str) -> TableSpec:
    d = _mapping(value, where, {"xyz", "rpy_deg", "size", "friction", "hydroelastic_modulus"})
    t = TableSpec()
    pose = _pose({k: d[k] for k in ("xyz", "rpy_deg") if k in d}, where, t.pose)
    size = _vec(d.get("size", t.size), 3, f"{where}.size")
    if min(size) <= 0:
        raise InputError(f"{where}.size: expected positive extents, got {list(size)}")
    return TableSpec(pose, size,
                     _num(d.get("friction", t.friction), f"{where}.friction", positive=True),
                     _num(d.get("hydroelastic_modulus", t.hydroelastic_modulus),
                          f"{where}.hydroelastic_modulus", positive=True))


_SCENARIO_FIELDS = {"object", "arm_base", "arm_q_home", "table", "cameras", "object_cloud", "plant", "meshcat"}


def scenario_from_dict(name: str, data: Any) -> Scenario:
    """Build a ``Scenario`` from one YAML entry (a mapping); raise InputError naming bad fields."""
    where = f"scenario {name!r}"
    d = _mapping(data, where, _SCENARIO_FIELDS)
    cams = d.get("cameras", None)
    if cams is None:
        cameras = Scenario.cameras
    else:
        if not isinstance(cams, list):
            raise InputError(f"{where}.cameras: expected a list of cameras")
        cameras = tuple(_camera(c, f"{where}.cameras[{i}]") for i, c in enumerate(cams))
        names = [c.name for c in cameras]
        if len(set(names)) != len(names):
            raise InputError(f"{where}.cameras: duplicate camera names {names}")
    meshcat = d.get("meshcat", False)
    if not isinstance(meshcat, bool):
        raise InputError(f"{where}.meshcat: expected true/false, got {meshcat!r}")
    return Scenario(
        name=name,
        object=_object(d.get("object"), f"{where}.object"),
        arm_base=_pose(d.get("arm_base"), f"{where}.arm_base"),
        arm_q_home=_vec(d.get("arm_q_home", DEFAULT_ARM_Q_HOME), 6, f"{where}.arm_q_home"),
        table=_table(d.get("table"), f"{where}.table"),
        cameras=cameras,
        object_cloud=_object_cloud(d.get("object_cloud"), f"{where}.object_cloud"),
        plant=_plant(d.get("plant"), f"{where}.plant"),
        meshcat=meshcat,
    )


def load_scenarios(path: str | Path = DEFAULT_SCENARIO_FILE) -> dict[str, Scenario]:
    """All named scenarios of a YAML file (``name -> Scenario``), in file order."""
    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text())
    except OSError as e:
        raise ModelFileError(f"{path}: cannot read scenario file ({e})") from None
    except yaml.YAMLError as e:
        raise InputError(f"{path}: not valid YAML ({e})") from None
    if not isinstance(data, dict) or not data:
        raise InputError(f"{path}: expected a mapping of scenario names to scenarios")
    return {str(name): scenario_from_dict(str(name), entry) for name, entry in data.items()}


def load_scenario(name: str, path: str | Path = DEFAULT_SCENARIO_FILE) -> Scenario:
    """One named scenario; InputError naming it (and the known names) when absent."""
    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text())
    except OSError as e:
        raise ModelFileError(f"{path}: cannot read scenario file ({e})") from None
    except yaml.YAMLError as e:
        raise InputError(f"{path}: not valid YAML ({e})") from None
    if not isinstance(data, dict) or name not in data:
        known = ", ".join(map(str, data)) if isinstance(data, dict) else "none"
        raise InputError(f"unknown scenario {name!r} in {path.name}; known: {known}")
    return scenario_from_dict(name, data[name])


def with_instance(scenario: Scenario, instance: str, category: str | None = None,
                  model_dir: str | None = None) -> Scenario:
    """``scenario`` with its object replaced by a data-set instance (or the one in ``model_dir``), same placement."""
    obj = dataclasses.replace(scenario.object, instance=instance, primitive=None,
                              category=category or scenario.object.category,
                              model_dir=None if model_dir is None else str(model_dir))
    return scenario.replace(name=f"{scenario.name}:{instance}", object=obj)


def random_placement(scenario: Scenario, seed: int, *, yaw_range_deg: float = 20.0,
                     shift_m: float = 0.03) -> Scenario:
    """``scenario`` with its object moved by a seeded random yaw (uniform, +-``yaw_range_deg`` about
    its yaw) and shift (uniform, +-``shift_m`` in x and y of the table frame).

    The default ranges keep the functional side (trigger, handle) within the
    right hand's reach; the same seed always gives the same placement.
    """
    rng = np.random.default_rng([int(seed), 20181])
    o = scenario.object
    dyaw = float(rng.uniform(-yaw_range_deg, yaw_range_deg))
    dx, dy = (float(v) for v in rng.uniform(-shift_m, shift_m, size=2))
    obj = dataclasses.replace(o, xyz=(o.xyz[0] + dx, o.xyz[1] + dy, o.xyz[2]), yaw_deg=o.yaw_deg + dyaw)
    return scenario.replace(name=f"{scenario.name}@seed{seed}", object=obj)
