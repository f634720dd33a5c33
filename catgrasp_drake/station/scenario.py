"""Station scenarios: a typed ``Scenario`` record loaded from YAML with named entries.

Style of Drake's ``examples/hardware_sim`` and the manipulation course's
``station.py``: every field has a default, a YAML entry only states what
differs (read by Drake's ``yaml_load_typed``), and one builder
(:mod:`catgrasp_drake.station.builder`) turns a ``Scenario`` into a diagram.

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
below; a malformed entry is an InputError naming the file, scenario and field)::

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

# (No ``from __future__ import annotations``: Drake's YAML loader reads the dataclasses' field types.)
import dataclasses
import math
import typing
from dataclasses import dataclass, field, fields, is_dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from pydrake.common.yaml import yaml_load_typed
from pydrake.math import RigidTransform, RollPitchYaw

from catgrasp_drake.core.visibility import look_at_matrix
from catgrasp_drake.data.dataset import CATEGORIES, list_instances, load_annotations, read_annotations
from catgrasp_drake.errors import InputError, ModelFileError

#: The project's scenario file.
DEFAULT_SCENARIO_FILE = Path(__file__).resolve().parents[2] / "models" / "station.scenarios.yaml"

# A field's rule, ``(ok(value) -> bool, what is expected)``, is checked on YAML input only (``_check``).
_POSITIVE = (lambda v: v > 0, "a positive number")
_NONNEG = (lambda v: v >= 0, "a non-negative number")


def _one_of(*options: str):
    return (lambda v: v in options, f"one of {options}")


def _f(default, rule=None):
    """A record field with a default and the rule its YAML value must pass."""
    return field(default=default, metadata={"rule": rule} if rule else {})


# ----------------------------------------------------------------------------- records
@dataclass(frozen=True)
class Pose:
    """A rigid transform as translation (m) + extrinsic roll-pitch-yaw (degrees)."""

    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy_deg: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def matrix(self) -> np.ndarray:
        """The 4x4 homogeneous transform (C-ordered)."""
        X = RigidTransform(RollPitchYaw(np.radians(self.rpy_deg)), np.array(self.xyz)).GetAsMatrix4()
        return np.ascontiguousarray(X)


@dataclass(frozen=True)
class PrimitiveObject:
    """A primitive test object (model name ``cylinder``/``box``, one link ``body``, base on z = 0)."""

    shape: str = _f("cylinder", _one_of("cylinder", "box"))  # "cylinder" (radius, length) or "box" (size)
    radius: float = _f(0.02, _POSITIVE)
    length: float = _f(0.15, _POSITIVE)
    size: tuple[float, float, float] = (0.05, 0.05, 0.15)
    mass_kg: float = _f(0.2, _POSITIVE)
    friction: float = _f(0.9, _POSITIVE)


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
    size: tuple[float, float, float] = _f((1.2, 1.4, 0.05), (lambda v: min(v) > 0, "positive extents"))
    friction: float = _f(0.6, _POSITIVE)
    hydroelastic_modulus: float = _f(1e7, _POSITIVE)


@dataclass(frozen=True)
class CameraSpec:
    """A fixed depth camera (RgbdSensor with RenderEngineVtk)."""

    name: str = _f("camera0", (str.isidentifier, "an identifier-like name"))
    X_WC: Pose | None = None
    look_at_eye: tuple[float, float, float] | None = (1.15, -0.45, 0.55)
    look_at_target: tuple[float, float, float] | None = (0.55, 0.0, 0.08)
    width: int = _f(640, _POSITIVE)
    height: int = _f(480, _POSITIVE)
    fov_y_deg: float = _f(45.0, (lambda v: 0 < v < 180, "an angle in (0, 180)"))
    depth_range: tuple[float, float] = _f((0.1, 3.0), (lambda v: 0 < v[0] < v[1], "0 < near < far"))

    def X_WC_matrix(self) -> np.ndarray:
        if self.X_WC is not None:
            return self.X_WC.matrix()
        return look_at_matrix(self.look_at_eye, self.look_at_target)


@dataclass(frozen=True)
class ObjectCloudSpec:
    """Post-processing of the segmented camera cloud (world frame, metres)."""

    voxel_size: float = _f(0.005, _NONNEG)
    crop_min: tuple[float, float, float] = (-0.5, -1.0, -0.02)
    crop_max: tuple[float, float, float] = (1.5, 1.0, 1.0)
    depth_noise_std: float = _f(0.0, _NONNEG)  # m; "kinect": the axial std at 1 m (it grows with depth squared)
    seed: int = _f(0, _NONNEG)
    depth_noise_model: str = _f("gaussian", _one_of("gaussian", "kinect"))  # perception.object_cloud._mask_depth
    #: "kinect": probability of dropping a silhouette / depth-jump pixel
    edge_dropout: float = _f(0.0, (lambda v: 0 <= v <= 1, "a probability in [0, 1]"))


@dataclass(frozen=True)
class PlantSpec:
    """MultibodyPlantConfig fields the station sets."""

    time_step: float = _f(5e-3, _POSITIVE)
    discrete_contact_approximation: str = _f("sap", _one_of("sap", "tamsi", "similar", "lagged", ""))
    contact_model: str = _f("hydroelastic_with_fallback",
                            _one_of("hydroelastic_with_fallback", "hydroelastic", "point"))
    penetration_allowance: float = _f(1e-3, _POSITIVE)
    #: SAP's near-rigid regime threshold (MultibodyPlantConfig; Drake's default 1.0, 0 turns it off): a speed
    #: lever of issue 17, measured by ``benchmarks/bench_fidelity.py --lever sap_near_rigid_threshold=V``.
    sap_near_rigid_threshold: float = _f(1.0, _NONNEG)
    #: Physics-sensitivity knobs (defaults: the station as tuned): the hand's effort limits times
    #: this factor (1/1.7: the real SVH's), and the object's Coulomb friction replaced (None: its SDF's).
    hand_effort_scale: float = _f(1.0, _POSITIVE)
    object_friction: float | None = _f(None, _POSITIVE)
    #: Speed lever (issue 17): the hand's compliant-hydroelastic mesh resolution hint (m) replaced
    #: (None: the model's 6 mm); coarser tessellations mean fewer contact polygons for SAP.
    hand_resolution_hint: float | None = _f(None, _POSITIVE)
    #: Robustness knob (grasp search): the object's mass (and with it its rotational inertia) times
    #: this factor, applied to the simulation context (``station.builder.apply_context_knobs``).
    object_mass_scale: float = _f(1.0, _POSITIVE)


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


# ----------------------------------------------------------------------------- YAML schema
# ``yaml_load_typed`` sets attributes and reads sequences as lists, so it cannot fill the frozen,
# tuple-valued records: it fills these mutable twins, laid out as the YAML is, with the records' defaults
# and rules; ``_check`` checks them, then they become records. (Drake's ``MultibodyPlantConfig`` and
# ``schema.Transform`` do not fit: ``plant`` holds the station's knobs beside the plant config's fields,
# and poses are ``{xyz, rpy_deg}``, not ``{translation, rotation}``.)
def _like(record: type, name: str):
    """A schema field with the default and rule of ``record``'s field ``name``."""
    f = record.__dataclass_fields__[name]
    return field(default=f.default, metadata=f.metadata)


def _twin(record: type) -> type:
    """The schema of a record the YAML spells out field by field (its tuples as lists)."""
    return dataclasses.make_dataclass(f"_{record.__name__}Yaml", [
        (f.name, list[float] if typing.get_origin(f.type) is tuple else f.type, _like(record, f.name))
        for f in fields(record)])


_PoseYaml, _PrimitiveYaml, _ObjectCloudYaml, _PlantYaml = map(_twin, (Pose, PrimitiveObject, ObjectCloudSpec,
                                                                      PlantSpec))


@dataclass
class _ObjectYaml:
    category: str | None = None  # None: ObjectSpec.category (for a data-set instance)
    instance: str | None = None  # None: "<category>_00"
    primitive: _PrimitiveYaml | None = None
    xyz: list[float] = ObjectSpec.xyz
    yaw_deg: float = ObjectSpec.yaw_deg
    model_dir: str | None = None


@dataclass
class _TableYaml:
    xyz: list[float] = TableSpec.pose.xyz
    rpy_deg: list[float] = TableSpec.pose.rpy_deg
    size: list[float] = _like(TableSpec, "size")
    friction: float = _like(TableSpec, "friction")
    hydroelastic_modulus: float = _like(TableSpec, "hydroelastic_modulus")


@dataclass
class _LookAtYaml:
    eye: list[float] = CameraSpec.look_at_eye
    target: list[float] = CameraSpec.look_at_target


@dataclass
class _CameraYaml:
    name: str = _like(CameraSpec, "name")
    X_WC: _PoseYaml | None = None
    look_at: _LookAtYaml | None = None  # None (and no X_WC): CameraSpec's look-at default
    width: int = _like(CameraSpec, "width")
    height: int = _like(CameraSpec, "height")
    fov_y_deg: float = _like(CameraSpec, "fov_y_deg")
    depth_range: list[float] = _like(CameraSpec, "depth_range")


@dataclass
class _ScenarioYaml:
    object: _ObjectYaml = field(default_factory=_ObjectYaml)
    arm_base: _PoseYaml = field(default_factory=_PoseYaml)
    arm_q_home: list[float] = DEFAULT_ARM_Q_HOME
    table: _TableYaml = field(default_factory=_TableYaml)
    cameras: list[_CameraYaml] | None = None  # None: Scenario.cameras
    object_cloud: _ObjectCloudYaml = field(default_factory=_ObjectCloudYaml)
    plant: _PlantYaml = field(default_factory=_PlantYaml)
    meshcat: bool = False


# ----------------------------------------------------------------------------- loading
#: What Drake's loader raises on bad data: its own RuntimeError, or (from inside it) a failed str -> number
#: conversion, a scalar where a list or mapping belongs, or data PyYAML cannot write back.
_LOADER_ERRORS = (RuntimeError, ValueError, TypeError, AttributeError, AssertionError, OverflowError, yaml.YAMLError)


def _one_line(e: Exception) -> str:
    return " ".join(str(e).split()) or type(e).__name__


def _load(schema: type, data: dict, where: str):
    """``data`` (plain YAML data) loaded by ``yaml_load_typed`` into ``schema``'s defaults."""
    try:
        return yaml_load_typed(schema=schema, data=yaml.safe_dump(data))
    except _LOADER_ERRORS as e:
        raise InputError(_blame(schema, data, where) or f"{where}: {_one_line(e)}") from None


def _blame(schema: type, data: Any, where: str) -> str | None:
    """The one-line error of the deepest field of ``data`` that Drake's loader rejects (its own messages
    name the leaf field at most): each field is loaded alone, and a failing mapping searched further."""
    if not isinstance(data, dict):
        return f"{where}: expected a mapping, got {type(data).__name__}"
    types = {f.name: f.type for f in fields(schema)}
    for key, value in data.items():
        w = f"{where}.{key}"
        if key not in types:
            return f"{where}: unknown field {key!r}; known: {', '.join(types)}"
        try:
            yaml_load_typed(schema=schema, data=yaml.safe_dump({key: value}))
        except _LOADER_ERRORS as e:
            args = typing.get_args(types[key])
            kind = args[0] if type(None) in args else types[key]  # X of X | None
            item = typing.get_args(kind)[0] if typing.get_origin(kind) is list else None
            if is_dataclass(kind):
                return _blame(kind, value, w)
            if item is not None and not isinstance(value, list):
                return f"{w}: expected a list, got {type(value).__name__}"
            blamed = (_blame(item, v, f"{w}[{i}]") for i, v in enumerate(value)) if is_dataclass(item) else ()
            return next(filter(None, blamed), f"{w}: {_one_line(e)}")
    return None


def _check(obj, where: str) -> None:
    """A loaded schema object's checks, recursively: every number finite, a vector exactly as long as its
    default, each field's rule; InputError naming the first field that fails."""
    for f in fields(obj):
        value, w = getattr(obj, f.name), f"{where}.{f.name}"
        if is_dataclass(value):
            _check(value, w)
        elif isinstance(value, list) and value and is_dataclass(value[0]):
            for i, item in enumerate(value):
                _check(item, f"{w}[{i}]")
        elif value is not None:
            n = len(f.default) if isinstance(f.default, tuple) else None
            if n is not None and len(value) != n:
                raise InputError(f"{w}: expected {n} numbers, got {value!r}")
            if any(isinstance(x, float) and not math.isfinite(x) for x in (value if n else [value])):
                raise InputError(f"{w}: expected {'finite numbers' if n else 'a finite number'}, got {value!r}")
            ok, expected = f.metadata.get("rule", (None, ""))
            if ok is not None and not ok(value):
                raise InputError(f"{w}: expected {expected}, got {value!r}")


def _frozen(record: type, obj):
    """The ``record`` with the fields of the schema object ``obj`` (lists as tuples)."""
    values = {f.name: getattr(obj, f.name) for f in fields(obj)}
    return record(**{k: tuple(v) if isinstance(v, list) else v for k, v in values.items()})


def _object(o: _ObjectYaml, where: str) -> ObjectSpec:
    placement = {"xyz": tuple(o.xyz), "yaw_deg": o.yaw_deg}
    if o.primitive is not None:
        if o.category is not None or o.instance is not None:
            raise InputError(f"{where}: give either primitive or category + instance, not both")
        return ObjectSpec(None, None, _frozen(PrimitiveObject, o.primitive), **placement)
    category = ObjectSpec.category if o.category is None else o.category
    instance = f"{category}_00" if o.instance is None else o.instance
    if category not in CATEGORIES:
        raise InputError(f"{where}.category: unknown category {category!r}; known: {', '.join(CATEGORIES)}")
    if o.model_dir is not None:
        if not (Path(o.model_dir) / f"{instance}.sdf").is_file():
            raise InputError(f"{where}.model_dir: no {instance}.sdf in {o.model_dir}")
    elif instance not in list_instances(category):
        raise InputError(f"{where}.instance: unknown instance {instance!r} of {category!r}")
    return ObjectSpec(category, instance, None, model_dir=o.model_dir, **placement)


def _camera(c: _CameraYaml, where: str) -> CameraSpec:
    if c.X_WC is not None and c.look_at is not None:
        raise InputError(f"{where}: give either X_WC or look_at, not both")
    if c.X_WC is not None:
        X_WC, eye, target = _frozen(Pose, c.X_WC), None, None
    else:
        look_at = c.look_at or _LookAtYaml()
        X_WC, eye, target = None, tuple(look_at.eye), tuple(look_at.target)
        if np.allclose(eye, target):
            raise InputError(f"{where}.look_at: eye and target coincide")
    return CameraSpec(c.name, X_WC, eye, target, c.width, c.height, c.fov_y_deg, tuple(c.depth_range))


def _scenario(name: str, data: Any, where: str) -> Scenario:
    data = {} if data is None else data
    if not isinstance(data, dict):
        raise InputError(f"{where}: expected a mapping, got {type(data).__name__}")
    s = _load(_ScenarioYaml, {k: v for k, v in data.items() if v is not None}, where)  # null: the default
    _check(s, where)
    cameras = Scenario.cameras if s.cameras is None else tuple(
        _camera(c, f"{where}.cameras[{i}]") for i, c in enumerate(s.cameras))
    names = [c.name for c in cameras]
    if len(set(names)) != len(names):
        raise InputError(f"{where}.cameras: duplicate camera names {names}")
    cloud, t = s.object_cloud, s.table
    if not all(a < b for a, b in zip(cloud.crop_min, cloud.crop_max)):
        raise InputError(f"{where}.object_cloud: crop_min must be below crop_max in every axis")
    return Scenario(
        name=name, object=_object(s.object, f"{where}.object"), arm_base=_frozen(Pose, s.arm_base),
        arm_q_home=tuple(s.arm_q_home),
        table=TableSpec(Pose(tuple(t.xyz), tuple(t.rpy_deg)), tuple(t.size), t.friction, t.hydroelastic_modulus),
        cameras=cameras, object_cloud=_frozen(ObjectCloudSpec, cloud), plant=_frozen(PlantSpec, s.plant),
        meshcat=s.meshcat)


def scenario_from_dict(name: str, data: Any) -> Scenario:
    """Build a ``Scenario`` from one YAML entry (a mapping); raise InputError naming bad fields."""
    return _scenario(name, data, f"scenario {name!r}")


def _read(path: Path) -> dict:
    """The mapping ``name -> entry`` of a scenario file."""
    try:
        data = yaml.safe_load(path.read_text())
    except OSError as e:
        raise ModelFileError(f"{path}: cannot read scenario file ({e})") from None
    except yaml.YAMLError as e:
        raise InputError(f"{path}: not valid YAML ({_one_line(e)})") from None
    if not isinstance(data, dict) or not data:
        raise InputError(f"{path}: expected a mapping of scenario names to scenarios")
    return data


def load_scenarios(path: str | Path = DEFAULT_SCENARIO_FILE) -> dict[str, Scenario]:
    """All named scenarios of a YAML file (``name -> Scenario``), in file order."""
    path = Path(path)
    return {str(k): _scenario(str(k), v, f"{path.name}: scenario {str(k)!r}") for k, v in _read(path).items()}


def load_scenario(name: str, path: str | Path = DEFAULT_SCENARIO_FILE) -> Scenario:
    """One named scenario; InputError naming it (and the known names) when absent."""
    path = Path(path)
    data = _read(path)
    if name not in data:
        raise InputError(f"unknown scenario {name!r} in {path.name}; known: {', '.join(map(str, data))}")
    return _scenario(name, data[name], f"{path.name}: scenario {name!r}")


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
