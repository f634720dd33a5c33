"""The benchmark: held-out objects, every method through the transfer diagram, varied placements.

Splits (nothing is tuned on any of them; the committed instances, seed 2018,
are the train/tune split):

``test``   generated instances from the fixed :data:`TEST_SEED`, written on
           demand into ``<data_dir>/test_seed<TEST_SEED>`` (not committed);
           the first ``instances_per_category`` of each category.
``ycb``    the real YCB scans with a functional part: 035 power drill, 022
           Windex bottle, 025 mug (optional extra ``.[ycb]``; prepared into
           ``<data_dir>/ycb`` with their stated alignments).
``ais``    the 11 real drills of the paper authors' data set (``../shared/datasets/ais_drills``,
           CAD-derived clouds on a ~1 cm grid, already in the canonical frame; never copied into the
           repository): imported by :func:`catgrasp_drake.data.importer.import_object` (Poisson
           surface, the category's density, the trigger transferred by the committed drill model's
           fit -- not annotated by hand, so "functional" is judged on an estimated trigger) into
           ``<data_dir>/ais``; those that stand on their base (8 of 11: drill_2, 3 and 9 fall over by
           themselves). Drills only; the environment variable ``CATGRASP_AIS_DRILLS`` names another
           folder of ``drill_<n>.pcd`` files.
``fresh``  generated instances from a seed the user draws (``data_seed``; neither :data:`TEST_SEED` nor the
           committed data set's): instances nobody has seen, not even the test split's readers, written on
           demand into ``<data_dir>/fresh_seed<data_seed>/<category>``. Its records carry ``data_seed``;
           one records file holds one seed.
``val``    generated instances from the fixed :data:`VAL_SEED` (drawn in session 37 with ``secrets``, before any
           of its objects existed), written on demand into ``<data_dir>/val_seed<VAL_SEED>``: a TUNING set
           of novel draws. The committed instances are the models' training instances and the stress split
           stretches them, so neither shows what a fit does on a shape the shape space never saw; this split
           does, and may be tuned on (its figures are not results). The first ``instances_per_category``.
``smoke``  the first two test drills, one placement, latent and rigid: the CI run.
``objects`` the user's imported objects (``catgrasp import-object``), one directory each in
           ``BenchmarkConfig.objects``; their records go to ``out/benchmark/``, not the committed tables.

Trials: for every (instance, view, trial index) a placement and a camera come
from :func:`trial_placement` -- seeded by (benchmark seed, instance, trial), so
the trials of one instance differ and every method meets the same ones: yaw
uniform within +-60 deg of the category's default, position within +-5 cm,
the single-view camera from one of :data:`VIEWPOINTS` (cycled by trial index,
jittered; elevation 20-50 deg, azimuth within +-45 deg of the default), and
Kinect-v2-like depth noise (:data:`KINECT_NOISE`, seeded per trial). Each
trial builds ``make_transfer_diagram(..., method=m)`` -- the product's own
diagram: perceive, estimate, predict, plan around the perceived shape, refuse
below ``min_confidence``, execute -- and the station's judge decides
(:mod:`catgrasp_drake.station.judge`). Trials run as cached tasks of
:func:`catgrasp_drake.runner.run_tasks` (local processes or Ray; an
interrupted run resumes), and the records (JSON lines) are written with
:func:`catgrasp_drake.benchmark.report.write_benchmark_records`.
"""

from __future__ import annotations

import functools
import math
import os
import time
import zlib
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from catgrasp_drake.core.fileio import atomic_write_text, file_sha256
from catgrasp_drake.core.visibility import camera_on_sphere_position
from catgrasp_drake.data.dataset import CATEGORIES, object_files_sha256
from catgrasp_drake.errors import InputError
from catgrasp_drake.transfer import VIEWS

#: The test split's data-set seed. Fixed; nothing (grasps, kernels, thresholds) is chosen on it.
TEST_SEED = 7919
#: The validation (tuning) split's data-set seed: novel generator draws that may be tuned on (``val``).
VAL_SEED = 902870906
SPLITS = ("test", "fresh", "val", "ycb", "ais", "stress", "smoke", "objects")
#: The YCB scans of each category that have the category's functional part.
YCB_BY_CATEGORY = {"drill": ("ycb_035",), "spray_bottle": ("ycb_022",), "mug": ("ycb_025",)}
BENCHMARK_METHODS = ("latent", "latent_map", "paper", "nearest", "rigid", "cpd")
#: Physics settings: the default, and the sensitivity ablations (run on a subset).
PHYSICS = ("default", "time_step_1e-3", "effort_1.0x", "friction_0.5")
#: The station's hand is ~1.7x as strong as the real SVH (models/svh/README.md): "effort_1.0x" undoes it.
SVH_STRENGTH_FACTOR = 1.7
YAW_RANGE_DEG = 60.0
SHIFT_M = 0.05
#: Single-view camera viewpoints (azimuth offset from the default camera's, elevation), degrees;
#: trial k uses VIEWPOINTS[k % 3], jittered by up to +-10 deg azimuth and +-5 deg elevation.
VIEWPOINTS = ((-30.0, 25.0), (0.0, 40.0), (30.0, 32.0))
AZIMUTH_JITTER_DEG = 10.0
ELEVATION_JITTER_DEG = 5.0
ELEVATION_RANGE_DEG = (20.0, 50.0)
AZIMUTH_RANGE_DEG = 45.0
#: Kinect-v2-like depth noise: axial std 1.5 mm at 1 m growing with depth squared, silhouette and
#: depth-jump pixels dropped with probability 0.5 (a few per cent of the object's pixels).
KINECT_NOISE = {"depth_noise_model": "kinect", "depth_noise_std": 0.0015, "edge_dropout": 0.5}


@dataclass(frozen=True)
class BenchmarkConfig:
    """What to run. SI units; ``workers`` None = all cores, 0 = in this process."""

    split: str = "test"
    categories: tuple[str, ...] = CATEGORIES
    methods: tuple[str, ...] = BENCHMARK_METHODS
    views: tuple[str, ...] = ("single",)
    placements: int = 3
    instances_per_category: int = 12
    instances: tuple[str, ...] | None = None  # restrict to these instance names
    objects: tuple[str, ...] = ()  # split "objects": the imported objects' directories
    data_seed: int | None = None  # split "fresh": the data-set seed of its generated instances
    seed: int = 0
    noise: bool = True
    physics: str = "default"
    min_confidence: float = 0.0
    data_dir: str = "out/benchmark/data"
    cache_dir: str = "out/benchmark/cache"
    workers: int | None = None
    ray: str | None = None

    def __post_init__(self):
        from catgrasp_drake.prediction import METHODS

        if self.split not in SPLITS:
            raise InputError(f"split: expected one of {SPLITS}, got {self.split!r}")
        for name, values, known in (("categories", self.categories, CATEGORIES), ("methods", self.methods, METHODS),
                                    ("views", self.views, VIEWS)):
            bad = [v for v in values if v not in known]
            if bad or not values:
                raise InputError(f"{name}: unknown or empty {bad or values}; known: {', '.join(known)}")
        if self.split == "objects" and not self.objects:
            raise InputError("split objects: give the imported objects' directories (catgrasp import-object)")
        if self.objects and self.split != "objects":
            raise InputError(f"objects: given for split {self.split!r}; they are the split 'objects'")
        if not all(isinstance(d, str) and d for d in self.objects):
            raise InputError(f"objects: expected directory names, got {self.objects!r}")
        if self.split == "fresh":
            from catgrasp_drake.data.dataset import DATASET_SEED

            if isinstance(self.data_seed, bool) or not isinstance(self.data_seed, int) or self.data_seed < 0:
                raise InputError("split fresh: give its data-set seed (--data-seed, a non-negative integer), "
                                 f"got {self.data_seed!r}")
            if self.data_seed in (TEST_SEED, DATASET_SEED, VAL_SEED):
                whose = {TEST_SEED: "the test split", DATASET_SEED: "the committed data set",
                         VAL_SEED: "the validation (tuning) split"}[self.data_seed]
                raise InputError(f"data_seed: {self.data_seed} is {whose}'s seed; a fresh split needs another")
        elif self.data_seed is not None:
            raise InputError(f"data_seed: only for the split 'fresh' (the split {self.split!r} has its own objects)")
        if self.physics not in PHYSICS:
            raise InputError(f"physics: expected one of {PHYSICS}, got {self.physics!r}")
        if not (isinstance(self.placements, int) and 1 <= self.placements <= 1000):
            raise InputError(f"placements: expected an integer in 1..1000, got {self.placements!r}")
        if not (isinstance(self.instances_per_category, int) and self.instances_per_category >= 1):
            raise InputError("instances_per_category: expected a positive integer, "
                             f"got {self.instances_per_category!r}")
        if not 0.0 <= self.min_confidence <= 1.0:
            raise InputError(f"min_confidence: expected a value in [0, 1], got {self.min_confidence}")


# ----------------------------------------------------------------------------- objects
@dataclass(frozen=True)
class BenchmarkObject:
    """One object of a split: ``model_dir`` holds ``<instance>.sdf``, ``.obj`` and ``annotations.json``."""

    split: str
    category: str
    instance: str
    model_dir: str


def test_split_dir(data_dir: str | Path, seed: int = TEST_SEED) -> Path:
    return Path(data_dir) / (f"test_seed{seed}" if seed == TEST_SEED else f"val_seed{seed}")


def ensure_test_split(data_dir: str | Path, seed: int = TEST_SEED) -> Path:
    """Generate the test split (all categories, :data:`TEST_SEED`; or the validation split, ``seed`` =
    :data:`VAL_SEED`) into ``data_dir`` unless it is there, made by the current generators (a changed
    generator regenerates it: its marker names their fingerprint)."""
    from catgrasp_drake.data.dataset import INSTANCE_COUNTS, generate_dataset

    root = test_split_dir(data_dir, seed)
    marker = root / "COMPLETE"
    stamp = f"seed {seed}, {sum(INSTANCE_COUNTS.values())} instances, generators {_generator_version()}"
    if not marker.is_file() or marker.read_text().strip() != stamp:
        generate_dataset(root, seed=seed)
        atomic_write_text(marker, stamp + "\n")
    return root


def _data_code_version(*modules: str) -> str:
    """Fingerprint of the ``catgrasp_drake/data`` modules that make a split's objects (changed code: made again)."""
    from catgrasp_drake.runner import code_fingerprint

    data = Path(__file__).resolve().parents[1] / "data"
    return code_fingerprint([data / f for f in modules])


def _generator_version() -> str:
    """Fingerprint of the code that generates the embedded categories' instances."""
    return _data_code_version("categories.py", "shapes.py", "dataset.py", "meshes.py")


def fresh_split_dir(data_dir: str | Path, data_seed: int) -> Path:
    return Path(data_dir) / f"fresh_seed{int(data_seed)}"


def ensure_fresh_split(data_dir: str | Path, data_seed: int, category: str) -> Path:
    """Generate ``category``'s instances of the data-set seed ``data_seed`` into
    ``<data_dir>/fresh_seed<data_seed>/<category>`` unless the current generators made them there."""
    from catgrasp_drake.data.dataset import INSTANCE_COUNTS, generate_dataset

    root = fresh_split_dir(data_dir, data_seed)
    marker = root / category / "COMPLETE"
    stamp = f"seed {data_seed}, {INSTANCE_COUNTS[category]} instances, generators {_generator_version()}"
    if not marker.is_file() or marker.read_text().strip() != stamp:
        generate_dataset(root, categories=(category,), seed=data_seed)
        atomic_write_text(marker, stamp + "\n")
    return root


def split_objects(config: BenchmarkConfig) -> list[BenchmarkObject]:
    """The objects of ``config.split`` for its categories (generated or prepared on demand)."""
    out = []
    if config.split in ("test", "smoke", "val"):
        from catgrasp_drake.data.dataset import INSTANCE_COUNTS, instance_name

        root = ensure_test_split(config.data_dir, VAL_SEED if config.split == "val" else TEST_SEED)
        categories = ("drill",) if config.split == "smoke" else config.categories
        for category in categories:
            n = 2 if config.split == "smoke" else min(config.instances_per_category, INSTANCE_COUNTS[category])
            for i in range(n):
                name = instance_name(category, i)
                out.append(BenchmarkObject(config.split, category, name, str(root / category / name)))
    elif config.split == "fresh":
        from catgrasp_drake.data.dataset import INSTANCE_COUNTS, instance_name

        for category in config.categories:
            root = ensure_fresh_split(config.data_dir, config.data_seed, category)
            for i in range(min(config.instances_per_category, INSTANCE_COUNTS[category])):
                name = instance_name(category, i)
                out.append(BenchmarkObject("fresh", category, name, str(root / category / name)))
    elif config.split == "objects":
        from catgrasp_drake.data.dataset import imported_object

        seen = {}
        for directory in config.objects:
            category, name = imported_object(directory)
            if name in seen:
                raise InputError(f"objects: {directory} and {seen[name]} are both named {name!r}; re-import one "
                                 "with --name")
            seen[name] = directory
            if category in config.categories:
                out.append(BenchmarkObject("objects", category, name, str(directory)))
    elif config.split == "ais":
        if "drill" in config.categories:
            out += _ais_drills(Path(config.data_dir) / "ais", config.instances)
    elif config.split == "stress":
        out += _stress_objects(Path(config.data_dir) / "stress", config.categories)
    else:  # ycb
        from catgrasp_drake.data.ycb import prepare_ycb, ycb_dir

        root = Path(config.data_dir) / "ycb"
        stamp = _ycb_preparation_version()
        for category in config.categories:
            for name in YCB_BY_CATEGORY[category]:
                directory = ycb_dir(name, root)
                _prepared(directory, name, stamp, functools.partial(prepare_ycb, root, [name]))
                out.append(BenchmarkObject("ycb", category, name, str(directory)))
    if config.instances is not None:
        out = [o for o in out if o.instance in config.instances]
    return out


def _prepared(directory: Path, name: str, stamp: str, prepare) -> None:
    """Call ``prepare()`` unless ``directory`` holds ``<name>.sdf`` and a ``PREPARED_BY`` marker saying ``stamp``
    (the version of the code that makes it), then write the marker."""
    marker = directory / "PREPARED_BY"
    if (directory / f"{name}.sdf").is_file() and marker.is_file() and marker.read_text().strip() == stamp:
        return
    prepare()  # absent, or made by another version of the import
    atomic_write_text(marker, stamp + "\n")


def ais_drills_dir() -> Path:
    """The folder of the real AIS drill clouds: ``$CATGRASP_AIS_DRILLS``, else ``../shared/datasets/ais_drills``
    beside the repository."""
    given = os.environ.get("CATGRASP_AIS_DRILLS")
    return Path(given) if given else Path(__file__).resolve().parents[3] / "shared" / "datasets" / "ais_drills"


#: The AIS drills' trigger boxes, pinned (``tools/pin_ais_triggers.py``): the judge of the ``ais`` split does not
#: move with the drill model under test.
AIS_TRIGGERS = Path(__file__).resolve().parent / "ais_triggers.json"


def _ais_drills(root: Path, only=None) -> list[BenchmarkObject]:
    """The AIS drills that stand on their base, as imported objects under ``root`` (imported again when the
    import code or the pinned triggers changed); InputError when their folder is absent.

    Each trigger box is the pinned one of :data:`AIS_TRIGGERS` (until session 21 it was transferred by the
    committed drill model's fit, so a retrained model moved its own judge)."""
    import json

    from catgrasp_drake.data.dataset import read_annotations
    from catgrasp_drake.data.importer import import_object

    source = ais_drills_dir()
    clouds = sorted(source.glob("drill_*.pcd"), key=lambda f: (len(f.stem), f.stem))  # drill_2 before drill_10
    if not clouds:
        raise InputError(f"split ais: no drill_<n>.pcd clouds in {source} (the shared data set is not beside the "
                         "repository; set CATGRASP_AIS_DRILLS to their folder)")
    triggers = json.loads(AIS_TRIGGERS.read_text())["triggers"]
    stamp = f"{_data_code_version('importer.py', 'meshes.py', 'dataset.py', 'cloud_io.py')} {file_sha256(AIS_TRIGGERS)}"

    def import_drill(cloud: Path, directory: Path, name: str) -> None:
        if name not in triggers:
            raise InputError(f"split ais: no pinned trigger for {name} in {AIS_TRIGGERS}")
        # the clouds are in the canonical frame already: the identity, stated; the trigger pinned
        import_object(cloud, "drill", transform="0 0 0 0 0 0", out=directory, name=name,
                      regions={"trigger": triggers[name]})

    out = []
    for cloud in clouds:
        name = f"ais_{cloud.stem}"
        if only is not None and name not in only:
            continue
        directory = root / "drill" / name
        _prepared(directory, name, stamp, functools.partial(import_drill, cloud, directory, name))
        if read_annotations(directory / "annotations.json")["import"]["stands"]:
            out.append(BenchmarkObject("ais", "drill", name, str(directory)))
        # else: it falls over by itself (drill_2, drill_3, drill_9: corded drills' narrow handle ends); no
        # grasp from the table can be tested on it
    return out


def stretched_objects(root: str | Path, category: str, instances, families) -> list[tuple[str, Path]]:
    """``instances`` (committed, of ``category``) stretched by each of ``families`` (names of
    ``data.stretch.STRESS_FAMILIES``), written under ``root/<category>/<instance>_<family>`` once (again when the
    stretch code or the source instance changed): ``[(name, directory)]``, family by family. The stress split's
    objects, and ``catgrasp train --stretch``'s."""
    from catgrasp_drake.data.dataset import instance_dir
    from catgrasp_drake.data.stretch import STRESS_FAMILIES, stretch_instance

    unknown = [f for f in families if f not in STRESS_FAMILIES]
    if unknown:
        raise InputError(f"stretch families: unknown {unknown}; known: {', '.join(STRESS_FAMILIES)}")
    code = _data_code_version("stretch.py", "dataset.py")
    sources = {instance: " ".join(file_sha256(instance_dir(category, instance) / f)
                                  for f in (f"{instance}.obj", "annotations.json"))
               for instance in instances}
    out = []
    for family in families:
        for instance, source in sources.items():
            name = f"{instance}_{family}"
            directory = Path(root) / category / name
            _prepared(directory, name, f"{code} {family} {source}",
                      functools.partial(stretch_instance, category, instance, STRESS_FAMILIES[family], directory,
                                        name))
            out.append((name, directory))
    return out


def _stress_objects(root: Path, categories) -> list[BenchmarkObject]:
    """Every committed instance of ``categories`` stretched by each of ``data.stretch.STRESS_FAMILIES``
    (:func:`stretched_objects`)."""
    from catgrasp_drake.data.dataset import list_instances
    from catgrasp_drake.data.stretch import STRESS_FAMILIES

    return [BenchmarkObject("stress", category, name, str(directory))
            for category in categories
            for name, directory in stretched_objects(root, category, list_instances(category), STRESS_FAMILIES)]


def _ycb_preparation_version() -> str:
    """Fingerprint of the code that turns a YCB scan into an instance (a changed import re-prepares them)."""
    return _data_code_version("ycb.py", "importer.py", "meshes.py", "dataset.py")


# ----------------------------------------------------------------------------- placements
def _rng(seed: int, instance: str, trial: int) -> np.random.Generator:
    return np.random.default_rng([int(seed), zlib.crc32(instance.encode("utf-8")), int(trial), 15])


def trial_placement(scenario, instance: str, trial: int, seed: int, *, noise: bool = True):
    """``(scenario, placement, camera)`` of one benchmark trial (module docstring).

    ``scenario`` is the category's default scenario holding the instance;
    the returned one has the object moved (yaw, shift in the table frame),
    the single camera re-posed about the moved object and, with ``noise``,
    Kinect-like depth noise seeded by the trial. ``placement`` and ``camera``
    are JSON-able records of what was drawn.
    """
    import dataclasses

    from catgrasp_drake.station.scenario import CameraSpec

    rng = _rng(seed, instance, trial)
    o = scenario.object
    dyaw = float(rng.uniform(-YAW_RANGE_DEG, YAW_RANGE_DEG))
    dx, dy = (float(v) for v in rng.uniform(-SHIFT_M, SHIFT_M, size=2))
    az_off, el = VIEWPOINTS[trial % len(VIEWPOINTS)]
    az_off = float(np.clip(az_off + rng.uniform(-AZIMUTH_JITTER_DEG, AZIMUTH_JITTER_DEG),
                           -AZIMUTH_RANGE_DEG, AZIMUTH_RANGE_DEG))
    el = float(np.clip(el + rng.uniform(-ELEVATION_JITTER_DEG, ELEVATION_JITTER_DEG), *ELEVATION_RANGE_DEG))
    noise_seed = int(rng.integers(0, 2**31 - 1))
    obj = dataclasses.replace(o, xyz=(o.xyz[0] + dx, o.xyz[1] + dy, o.xyz[2]), yaw_deg=o.yaw_deg + dyaw)
    R_WT = scenario.table.pose.matrix()[:3, :3]
    shift_W = R_WT @ np.array([dx, dy, 0.0])
    base = scenario.cameras[0] if scenario.cameras else CameraSpec()
    X_WC = base.X_WC_matrix()
    target0 = np.asarray(base.look_at_target if base.look_at_target is not None else
                         X_WC[:3, 3] + 0.8 * X_WC[:3, 2], float)
    offset = X_WC[:3, 3] - target0
    distance = float(np.linalg.norm(offset))
    az0 = math.degrees(math.atan2(offset[1], offset[0]))
    az = az0 + az_off
    target = target0 + shift_W
    eye = camera_on_sphere_position(target, distance, math.radians(az), math.radians(el))
    camera = dataclasses.replace(base, X_WC=None, look_at_eye=tuple(float(v) for v in eye),
                                 look_at_target=tuple(float(v) for v in target))
    cloud = scenario.object_cloud
    if noise:
        cloud = dataclasses.replace(cloud, seed=noise_seed, **KINECT_NOISE)
    placed = scenario.replace(name=f"{scenario.name}@trial{trial}", object=obj, cameras=(camera,),
                              object_cloud=cloud)
    placement = {"yaw_deg": round(obj.yaw_deg, 6), "dyaw_deg": round(dyaw, 6),
                 "xyz": [round(float(v), 6) for v in obj.xyz]}
    cam = {"azimuth_deg": round(az, 3), "azimuth_offset_deg": round(az_off, 3), "elevation_deg": round(el, 3),
           "distance_m": round(distance, 4), "viewpoint": trial % len(VIEWPOINTS),
           "noise": KINECT_NOISE | {"seed": noise_seed} if noise else None}
    return placed, placement, cam


def with_physics(scenario, physics: str):
    """``scenario`` with a physics-sensitivity setting (:data:`PHYSICS`) applied."""
    if physics == "default":
        return scenario
    if physics == "time_step_1e-3":
        return scenario.replace(plant=replace(scenario.plant, time_step=1e-3))
    if physics == "effort_1.0x":
        return scenario.replace(plant=replace(scenario.plant, hand_effort_scale=1.0 / SVH_STRENGTH_FACTOR))
    if physics == "friction_0.5":
        return scenario.replace(plant=replace(scenario.plant, object_friction=0.5))
    raise InputError(f"physics: expected one of {PHYSICS}, got {physics!r}")


def trial_scenario(spec: dict):
    """The scenario of one trial spec: default scenario of the category, the object, placement, physics."""
    from catgrasp_drake.station.scenario import load_scenario, with_instance

    base = with_instance(load_scenario(f"{spec['category']}_default"), spec["instance"], category=spec["category"],
                         model_dir=spec["model_dir"])
    placed, placement, camera = trial_placement(base, spec["instance"], spec["trial"], spec["seed"],
                                                noise=spec["noise"])
    return with_physics(placed, spec["physics"]), placement, camera


# ----------------------------------------------------------------------------- the trial task
#: What a trial's record copies from its spec (the trial's identity and settings).
TRIAL_KEYS = ("split", "category", "instance", "trial", "view", "method", "physics", "seed", "min_confidence", "noise")
_MODELS: dict = {}


def _model(path: str, category: str):
    from catgrasp_drake.category_model import CategoryModel

    key = (path, category)
    if key not in _MODELS:
        _MODELS[key] = CategoryModel.load(path, category=category)
    return _MODELS[key]


def yaw_error_deg(X_WO_estimated, X_WO_true) -> float:
    """Signed angle (deg, in (-180, 180]) about the world z from the true object's functional direction (+y of O,
    projected on the table) to the estimated one: which way round the object was fitted."""
    y_est, y_true = np.asarray(X_WO_estimated, float)[:2, 1], np.asarray(X_WO_true, float)[:2, 1]
    return math.degrees(math.atan2(y_true[0] * y_est[1] - y_true[1] * y_est[0], float(y_true @ y_est)))


def trial_identity(spec: dict) -> dict:
    """The record fields a trial's spec fixes: :data:`TRIAL_KEYS` and, for the fresh split, ``data_seed``."""
    return {k: spec[k] for k in TRIAL_KEYS} | ({"data_seed": spec["data_seed"]} if "data_seed" in spec else {})


def benchmark_trial_task(spec: dict) -> dict:
    """Worker task: one benchmark trial (spec from :func:`trial_specs`) -> its record (JSON-able)."""
    from catgrasp_drake.transfer import make_transfer_diagram, run_transfer

    t0 = time.perf_counter()
    model = _model(spec["_model"], spec["category"])
    scenario, placement, camera = trial_scenario(spec)
    td = make_transfer_diagram(scenario, model, view=spec["view"], method=spec["method"],
                               min_confidence=spec["min_confidence"])
    build_s = time.perf_counter() - t0
    result = run_transfer(td)
    timings = {k: round(float(v), 4) for k, v in result.timings.items()} | {"build": round(build_s, 4)}
    timings["total"] = round(time.perf_counter() - t0, 4)
    record = trial_identity(spec)
    measured = {k: (None if not math.isfinite(v) else round(v, 6)) for k, v in result.judge.items()}
    return record | {
        "grasp": bool(result.grasp_success), "functional": bool(result.functional_success),
        "reason": result.failure_reason, "detail": result.detail, "plan_status": result.plan_status,
        "confidence": round(float(result.confidence), 6), "scale": round(float(result.scale), 6),
        "num_points": int(result.num_observed_points), "placement": placement, "camera": camera,
        "pose_error_mm": round(1000 * float(np.linalg.norm(np.array(result.X_WO_estimated)[:3, 3]
                                                           - np.array(result.X_WO_true)[:3, 3])), 3),
        "yaw_error_deg": round(yaw_error_deg(result.X_WO_estimated, result.X_WO_true), 3),
        "rise_m": round(float(result.object_rise_m), 6), "tilt_deg": round(float(result.object_tilt_deg), 4),
        "judge": measured, "timings": timings, "model_sha256": spec["model_sha256"],
        "posterior": {k: (round(v, 6) if isinstance(v, float) else v) for k, v in result.posterior.items()},
        "views_used": int(result.views_used),
    }


def benchmark_code_version() -> str:
    """Fingerprint of everything a trial's outcome depends on (the package, the models, the scenarios)."""
    from catgrasp_drake.runner import code_fingerprint

    root = Path(__file__).resolve().parents[2]
    return code_fingerprint([root / "catgrasp_drake", root / "models"])


def trial_specs(config: BenchmarkConfig, model_paths: dict[str, str] | None = None) -> list[dict]:
    """One task spec per (object, view, trial, method); methods share each trial's placement and camera."""
    from catgrasp_drake.demo import default_model_path

    specs = []
    models = {}
    placements = 1 if config.split == "smoke" else config.placements
    for obj in split_objects(config):
        if obj.category not in models:
            path = Path((model_paths or {}).get(obj.category) or default_model_path(obj.category))
            models[obj.category] = (str(path), file_sha256(path))
        path, sha = models[obj.category]
        # an imported object may be re-imported into the same directory, a YCB scan prepared again by a changed
        # import and a generated split made again by changed generators: its files are part of the cache key
        own = {"object_sha256": object_files_sha256(obj.model_dir, obj.instance)}
        if obj.split == "fresh":
            own["data_seed"] = int(config.data_seed)
        for view in config.views:
            for trial in range(placements):
                for method in config.methods:
                    specs.append(own | {"task": "benchmark_trial", "split": obj.split, "category": obj.category,
                                  "instance": obj.instance, "model_dir": obj.model_dir, "trial": trial,
                                  "view": view, "method": method, "physics": config.physics, "seed": config.seed,
                                  "noise": bool(config.noise), "min_confidence": float(config.min_confidence),
                                  "_model": path, "model_sha256": sha})
    return specs


def observed_views(config: BenchmarkConfig):
    """Every trial of ``config`` (single view, one method) seen once by the station camera, nothing simulated.

    Yields ``(spec, model, scenario, placement, camera, p_W, camera_W)``:
    - the trial's spec (:func:`trial_specs`) and its category's model, loaded once per category;
    - the trial's scenario, placement and camera, as :func:`trial_scenario` gives them (the records' fields);
    - the object's cloud in W (N, 3) m and the camera position in W (3,) (:func:`catgrasp_drake.transfer.observe`).

    It is for probing the estimator over a split without simulating (e.g. the session-48 probes in
    ``benchmarks/results/experiments``). InputError unless ``config`` has one view, "single", and one method.
    """
    from catgrasp_drake.category_model import CategoryModel
    from catgrasp_drake.transfer import observe

    if tuple(config.views) != ("single",) or len(config.methods) != 1:
        raise InputError(f"observed_views: expected views ('single',) and one method, got views "
                         f"{tuple(config.views)} and methods {tuple(config.methods)}")
    models = {}
    for spec in trial_specs(config):
        if spec["category"] not in models:
            models[spec["category"]] = CategoryModel.load(spec["_model"], category=spec["category"])
        scenario, placement, camera = trial_scenario(spec)
        p_W, camera_W = observe(scenario)
        yield spec, models[spec["category"]], scenario, placement, camera, p_W, camera_W


def run_benchmark(config: BenchmarkConfig, *, model_paths: dict[str, str] | None = None, progress=None) -> list[dict]:
    """Run every trial of ``config`` (cached, resumable) and return the records in spec order.

    ``progress(outcome, done, total)`` as in :func:`catgrasp_drake.runner.run_tasks`.
    A trial that crashed its worker becomes a failed record with reason ``worker_died``.
    """
    from catgrasp_drake.runner import run_tasks

    specs = trial_specs(config, model_paths)
    version = benchmark_code_version()
    outcomes = run_tasks(benchmark_trial_task, specs, cache_dir=config.cache_dir, code_version=version,
                         workers=config.workers, progress=progress, ray_address=config.ray)
    records = []
    for spec, outcome in zip(specs, outcomes):
        r = dict(outcome.result)
        if "grasp" not in r:  # a dead worker or an exception inside the task: a failed trial, said so
            r = trial_identity(spec) | {
                "grasp": False, "functional": False,
                "reason": "worker_died" if r.get("worker_died") else "task_error",
                "detail": str(r.get("error", r))[:300], "timings": {}}
        records.append(r | {"code_version": version})
    return records


# ----------------------------------------------------------------------------- one trial again
def spec_from_record(record: dict, *, data_dir: str | Path = "out/benchmark/data", objects=()) -> dict:
    """The task spec that made a benchmark ``record`` (split, object, placement, camera, method, physics).

    The split's objects are generated or prepared again under ``data_dir``
    if needed; an ``objects``-split record needs its directory in ``objects``.
    """
    from catgrasp_drake.data.dataset import INSTANCE_COUNTS

    missing = [k for k in TRIAL_KEYS if k not in record]
    if missing:
        raise InputError(f"record: not a benchmark trial record (missing {', '.join(missing)})")
    config = BenchmarkConfig(
        split=record["split"], categories=(record["category"],), methods=(record["method"],),
        views=(record["view"],), placements=int(record["trial"]) + 1, instances=(record["instance"],),
        data_seed=record.get("data_seed"),
        instances_per_category=max(INSTANCE_COUNTS.values()), objects=tuple(objects), seed=int(record["seed"]),
        noise=bool(record["noise"]), physics=record["physics"], min_confidence=float(record["min_confidence"]),
        data_dir=str(data_dir))
    specs = [s for s in trial_specs(config) if s["trial"] == record["trial"]]
    if len(specs) != 1:
        raise InputError(f"record: no trial {record['trial']} of {record['instance']!r} in split {record['split']!r}"
                         + (" (pass the imported object's directory)" if record["split"] == "objects" else ""))
    return specs[0]


def film_benchmark_trial(record: dict, path: str | Path, *, data_dir: str | Path = "out/benchmark/data",
                         objects=(), closeup: bool = False, size: tuple[int, int] | None = None):
    """Run the trial of a benchmark ``record`` again through the transfer diagram and film it into ``path``
    (PNG, :mod:`catgrasp_drake.film`; ``closeup``: views that follow the functional region; ``size`` of a
    frame, pixels). Returns
    ``(TransferResult, spec)``; a model file that changed since the record shows in
    ``spec["model_sha256"] != record["model_sha256"]``."""
    from catgrasp_drake.film import film_transfer
    from catgrasp_drake.transfer import make_transfer_diagram

    spec = spec_from_record(record, data_dir=data_dir, objects=objects)
    scenario, _, _ = trial_scenario(spec)
    td = make_transfer_diagram(scenario, _model(spec["_model"], spec["category"]), view=spec["view"],
                               method=spec["method"], min_confidence=spec["min_confidence"])
    title = f"{spec['instance']} trial {spec['trial']} {spec['method']} ({spec['view']} view)"
    return film_transfer(td, path, title=title, closeup=closeup, size=size), spec
