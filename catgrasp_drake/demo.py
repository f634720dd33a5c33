"""``catgrasp demo``: the grasp transfer diagram on the embedded default data (the README's main job).

A trained category model (committed under ``models/trained``) meets an
instance it was never trained on, placed on the table at a seeded random yaw
and position and seen from one depth camera (or four, ``--view full``). The
transfer diagram (:mod:`catgrasp_drake.transfer`) perceives, estimates the
latent shape and pose, regresses and warps the grasp, plans and executes it
with the UR10 and the SVH hand, and the judge says whether it worked. One line
per stage with its time; a self-contained Meshcat HTML recording, a PNG
snapshot from the camera at the end of the hold and a JSON record are written
to ``--out``.
"""

from __future__ import annotations

import io
import json
import time
from pathlib import Path

import numpy as np
from PIL import Image

from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.core.fileio import atomic_write_bytes, atomic_write_text
from catgrasp_drake.core.rotations import rotation_angle
from catgrasp_drake.data.dataset import CATEGORIES, imported_object, list_instances, models_dir
from catgrasp_drake.errors import InputError, ModelFileError
from catgrasp_drake.station.scenario import load_scenario, random_placement, with_instance
from catgrasp_drake.transfer import make_transfer_diagram, run_transfer
from catgrasp_drake.viz.meshcat_tools import start_meshcat
from catgrasp_drake.viz.render import rgb_array


def _stage(name: str, seconds: float, detail: str) -> None:
    print(f"  {name:<9s} {seconds:7.2f} s  {detail}")


def default_model_path(category: str) -> Path:
    return models_dir() / "trained" / f"{category}.npz"


def pick_novel_instance(model, requested: str | None) -> str:
    """``requested``, or the last instance of the category the model was not trained on."""
    names = list_instances(model.category)
    if requested is not None:
        if requested not in names:
            raise InputError(f"unknown {model.category} instance {requested!r}; known: {', '.join(names)}")
        return requested
    novel = [n for n in names if n not in model.instances]
    if not novel:
        raise InputError(f"the {model.category} model was trained on every instance; pass --instance")
    return novel[-1]


def _snapshot_png(td, context, path: Path) -> None:
    """The first camera's colour image at the current time, as a PNG."""

    sensor = next(iter(td.station.cameras.values()))
    image = sensor.color_image_output_port().Eval(sensor.GetMyContextFromRoot(context))
    buf = io.BytesIO()
    Image.fromarray(rgb_array(image)).save(buf, format="PNG")
    atomic_write_bytes(path, buf.getvalue())


def run_demo(args) -> int:
    t_start = time.perf_counter()
    out = Path(args.out)
    category = args.category
    object_dir = getattr(args, "object", None)
    if object_dir is not None:
        if args.instance is not None:
            raise InputError("--instance and --object: give one object, not both")
        obj_category, obj_instance = imported_object(object_dir)
        if category is not None and category != obj_category:
            raise InputError(f"--category {category} but the --object is a {obj_category}")
        category = obj_category
    category = category or "drill"
    if args.model is None and category not in CATEGORIES:
        raise InputError(f"unknown category {category!r}; known: {', '.join(CATEGORIES)}")
    if not 0.0 <= args.min_confidence <= 1.0:
        raise InputError(f"--min-confidence: expected a value in [0, 1], got {args.min_confidence}")
    path = Path(args.model) if args.model else default_model_path(category)
    if not path.is_file():
        raise ModelFileError(f"{path}: no trained {category} model; run 'catgrasp train {category}' "
                             "or pass --model")
    t0 = time.perf_counter()
    model = CategoryModel.load(path, category=category)
    _stage("model", time.perf_counter() - t0, f"{model.category}: q = {model.space.q} latent dimensions, trained on "
           f"{len(model.instances)} instances ({path})")

    base = load_scenario(f"{model.category}_default")
    if object_dir is not None:
        instance, novel = obj_instance, f"imported from {object_dir}"
        scenario = random_placement(with_instance(base, instance, model.category, model_dir=str(object_dir)),
                                    args.seed)
    else:
        instance = pick_novel_instance(model, args.instance)
        novel = "never seen in training" if instance not in model.instances else "a TRAINING instance"
        scenario = random_placement(with_instance(base, instance), args.seed)
    o = scenario.object
    meshcat = None if args.no_meshcat else start_meshcat()
    t0 = time.perf_counter()
    td = make_transfer_diagram(scenario, model, meshcat, view=args.view, min_confidence=args.min_confidence)
    _stage("diagram", time.perf_counter() - t0,
           f"{instance} ({novel}) at yaw {o.yaw_deg:.1f} deg, ({o.xyz[0]:+.3f}, {o.xyz[1]:+.3f}) m on the table; "
           f"{args.view} view ({len(td.station.cameras)} camera{'s' if len(td.station.cameras) > 1 else ''})")

    html = out / "transfer.html" if meshcat is not None else None
    result, context = run_transfer(td, record_html=html, return_context=True)
    t = result.timings
    X_est, X_true = np.array(result.X_WO_estimated), np.array(result.X_WO_true)
    pos_err = 1000 * np.linalg.norm(X_est[:3, 3] - X_true[:3, 3])
    rot_err = np.degrees(rotation_angle(X_est[:3, :3].T @ X_true[:3, :3]))
    _stage("perceive", t["perceive"], f"{result.num_observed_points} object points (depth + label image -> "
           "segmented, cropped, voxelised cloud in W)")
    views = f", {result.views_used} camera views" if result.views_used > 1 else ""
    _stage("estimate", t["estimate"], f"latent shape + pose (unknown yaw{views}): scale {result.scale:.3f}, pose error "
           f"{pos_err:.1f} mm / {rot_err:.1f} deg, confidence {result.confidence:.2f}")
    _stage("regress", t["regress"], "grasp motion predicted, warped by W(x), placed in W")
    _stage("plan", t["plan"], f"IK plan: {result.plan_status}")
    if "execute" in t:
        _stage("execute", t["execute"],
               f"{t['simulated_s']:.2f} s simulated (approach, reach, close, lift, hold, shake, press)")
    verdict = (result.plan_status if result.failure_reason == "refused" else
               f"FUNCTIONAL GRASP (held through the shake, index finger pressing the trigger with "
               f"{result.judge.get('trigger_force_N', float('nan')):.0f} N)" if result.functional_success and
               model.category != "mug" else "FUNCTIONAL GRASP" if result.functional_success else
               f"grasped, not functional: {result.failure_reason} ({result.detail})" if result.grasp_success else
               f"failed: {result.failure_reason} ({result.detail})")
    _stage("judge", 0.0, f"{verdict}; object rose {100 * result.object_rise_m:.1f} cm, tilt "
           f"{result.object_tilt_deg:.1f} deg")

    t0 = time.perf_counter()
    out.mkdir(parents=True, exist_ok=True)
    png = out / "transfer.png"
    _snapshot_png(td, context, png)
    record = result.to_dict() | {"scenario": scenario.name, "seed": args.seed, "model": str(path)}
    atomic_write_text(out / "result.json", json.dumps(record, indent=1, default=float) + "\n")
    written = [str(p) for p in (html, png, out / "result.json") if p is not None]
    _stage("write", time.perf_counter() - t0, ", ".join(written))
    print(f"done in {time.perf_counter() - t_start:.1f} s")
    return 0
