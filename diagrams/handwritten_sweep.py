"""Run the hand-written grasp of each category on EVERY instance and tabulate the outcomes.

    python diagrams/handwritten_sweep.py [--categories drill spray_bottle mug] [--workers 2]
                                         [--cache out/handwritten_sweep_cache] [--json out/handwritten_sweep.json]
                                         [--shift DX DY DZ] [--rotate RX RY RZ] [--yaw DEG] [--model FILE]
                                         [--posture NAME.JOINT=RAD ...]
                                         [--objects DIR...] [--placements N] [--no-object-clearance]
                                         [--mass-scale S] [--plan FIELD=VALUE ...]

Each trial uses the category's default scenario (``<category>_default`` in
``models/station.scenarios.yaml``) with the object replaced by the instance,
and the hand-written grasp ``models/grasps/<category>_handwritten.yaml``
anchored to the instance's annotated region (``load_handwritten_motion``).
``--shift`` (m) and ``--rotate`` (deg, object-frame x-y-z Euler angles about
the anchor region's centre) move the whole grasp in the object frame, and ``--yaw`` (deg) turns it
about the object frame's vertical axis (z through the origin) afterwards: the way
to try a change to a hand-written grasp, and to see how far off a predicted
grasp may land before it fails; ``--posture closed.svh_pinky=0.856`` sets
one joint of one hand posture of every grasp (rad), the way to try a
posture change. ``--model FILE`` (a trained model of ONE
category) runs the model's learned grasp instead on each of its training
instances -- the regressed grasp R(x_i) warped by W(x_i), exactly what the
transfer executes under perfect perception -- so ``--shift`` shows how sharp
the learned knowledge's optimum is (on the instances it was learned from).
Trials run in parallel worker processes through
:func:`catgrasp_drake.runner.run_tasks` and are cached on disk by (spec, code
fingerprint), so a re-run only computes what changed. Prints one table row
per instance (grasp, functional, failure reason, the in-hand shift and turn,
and how far the planner's object clearance moved the grasp) and a summary per
category.

``--objects DIR...`` runs imported objects instead (``catgrasp
import-object``, or the YCB scans prepared by ``python -m
catgrasp_drake.data.ycb --out out/ycb``), each with its own category's
grasp anchored on its own annotation; ``--placements N`` runs each object at
N seeded random placements (``random_placement``, seeds 0..N-1);
``--mass-scale S`` scales each object's mass and rotational inertia (``PlantSpec.object_mass_scale``;
e.g. 3: a generated bottle about as heavy as a full real one).
``--plan close_time=1.6`` sets a field of the planner's ``PlanParams`` for every trial (timing, tolerances).
``--no-object-clearance`` plans without the object clearance (the planner as
it was before session 9), for a before/after in one command::

    python diagrams/handwritten_sweep.py --objects out/ycb/drill/ycb_035 out/ycb/spray_bottle/ycb_022 \
        out/ycb/mug/ycb_025 --placements 6 [--no-object-clearance]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CATEGORIES = ("drill", "spray_bottle", "mug")


def sweep_task(spec: dict) -> dict:
    """One trial: ``{"category", "instance"}`` -> JSON-able outcome (module-level: runs in workers)."""
    from catgrasp_drake.planning.records import PlanParams
    from catgrasp_drake.station.handwritten import load_handwritten_motion, moved_about, shifted_motion, with_postures
    from catgrasp_drake.station.scenario import load_scenario, random_placement, with_instance
    from catgrasp_drake.trial import run_grasp_trial

    category, instance, model_dir = spec["category"], spec["instance"], spec.get("model_dir")
    scenario = with_instance(load_scenario(f"{category}_default"), instance, category=category, model_dir=model_dir)
    if spec.get("seed") is not None:
        scenario = random_placement(scenario, spec["seed"])
    if spec.get("mass_scale"):
        scenario = scenario.replace(plant=dataclasses.replace(scenario.plant, object_mass_scale=spec["mass_scale"]))
    motion = learned_motion(spec["model"], category, instance) if spec.get("model") else \
        load_handwritten_motion(category, instance, spec.get("grasp_file"), annotations_dir=model_dir)
    if spec.get("postures"):
        motion = with_postures(motion, spec["postures"])
    if spec.get("shift") or spec.get("rotate"):
        motion = shifted_motion(motion, category, instance, spec.get("shift") or (0, 0, 0),
                                spec.get("rotate") or (0, 0, 0), annotations_dir=model_dir)
    if spec.get("yaw"):  # about the object frame's vertical axis: the grasp a yaw error of this much would give
        motion = moved_about(motion, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, spec["yaw"]))
    params = PlanParams(**spec.get("plan", {}))
    if spec.get("no_object_clearance"):
        params = dataclasses.replace(params, object_penetration_tol=None)
    r = run_grasp_trial(scenario, motion, params=params)
    return {
        "grasp": r.grasp_success, "functional": r.functional_success, "reason": r.failure_reason,
        "detail": r.detail, "plan_status": r.plan_status, "rise_m": r.object_rise_m,
        "tilt_deg": r.object_tilt_deg, "hand_links": list(r.hand_links_on_object),
        "sim_time_s": r.sim_time_s, "wall_time_s": r.wall_time_s,
        "trigger_force_N": r.trigger_force_N, "in_hand_shift_m": r.in_hand_shift_m,
        "in_hand_turn_deg": r.in_hand_turn_deg, "object_shift_mm": r.object_shift_mm,
    }


_MODELS: dict = {}


def learned_motion(path: str, category: str, instance: str):
    """The model's learned grasp for its training instance ``instance`` (object frame): R(x_i) warped by W(x_i)."""
    from catgrasp_drake.category_model import CategoryModel

    if (path, category) not in _MODELS:
        _MODELS[(path, category)] = CategoryModel.load(path, category=category)
    model = _MODELS[(path, category)]
    k = list(model.instances).index(instance)
    return model.transfer(model.space.latent_train[k], frame="object")


def posture_overrides(items: list[str], error) -> dict:
    """``["closed.svh_pinky=0.856", ...]`` -> ``{"closed": {"svh_pinky": 0.856}}``; ``error(message)`` on a
    malformed item (the joint and posture names are checked when the motion is made)."""
    out: dict = {}
    for item in items:
        name, _, value = item.partition("=")
        posture, _, joint = name.partition(".")
        try:
            angle = float(value)
        except ValueError:
            angle = None
        if not posture or not joint or angle is None:
            error(f"--posture: expected NAME.JOINT=RAD (e.g. closed.svh_pinky=0.856), got {item!r}")
        out.setdefault(posture, {})[joint] = angle
    return out


def plan_overrides(items: list[str], error) -> dict:
    """``["close_time=1.6", ...]`` -> ``{"close_time": 1.6}`` (PlanParams number fields); ``error(message)`` on an
    unknown field or a value that is not a number."""
    from catgrasp_drake.planning.records import PlanParams

    fields = {f.name: f for f in dataclasses.fields(PlanParams)}
    out: dict = {}
    for item in items:
        name, _, value = item.partition("=")
        if name not in fields:
            error(f"--plan: unknown PlanParams field {name!r} (fields: {', '.join(fields)})")
        try:
            number = float(value)
        except ValueError:
            error(f"--plan: expected FIELD=NUMBER, got {item!r}")
        out[name] = int(number) if isinstance(getattr(PlanParams(), name), int) else number
    return out


def _fmt(value, width: int, digits: int, scale: float = 1.0) -> str:
    """``value * scale`` right-aligned, or "-" when it was not measured (None)."""
    return f"{'-':>{width}s}" if value is None else f"{value * scale:{width}.{digits}f}"


def code_version() -> str:
    from catgrasp_drake.runner import code_fingerprint

    return code_fingerprint([ROOT / "catgrasp_drake", ROOT / "models" / "svh", ROOT / "models" / "grasps",
                             ROOT / "models" / "station.scenarios.yaml"])


def main(argv=None) -> int:
    from catgrasp_drake.data.dataset import list_instances
    from catgrasp_drake.runner import run_tasks

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--categories", nargs="+", default=list(CATEGORIES), choices=CATEGORIES)
    ap.add_argument("--instances", nargs="*", help="only these instances")
    ap.add_argument("--workers", type=int, default=None, help="worker processes (default: all cores)")
    ap.add_argument("--cache", type=Path, default=ROOT / "out" / "handwritten_sweep_cache")
    ap.add_argument("--no-cache", action="store_true")
    ap.add_argument("--json", type=Path, default=ROOT / "out" / "handwritten_sweep.json")
    ap.add_argument("--shift", type=float, nargs=3, metavar=("DX", "DY", "DZ"),
                    help="move every grasp by this (m, object frame)")
    ap.add_argument("--rotate", type=float, nargs=3, metavar=("RX", "RY", "RZ"),
                    help="turn every grasp about its anchor region's centre (deg, object-frame x-y-z Euler angles)")
    ap.add_argument("--yaw", type=float, default=0.0, metavar="DEG",
                    help="then turn every grasp about the object frame's vertical axis (deg): what a perception "
                         "whose yaw is off by this much would execute")
    ap.add_argument("--posture", nargs="+", action="extend", default=[], metavar="NAME.JOINT=RAD",
                    help="set one joint of one posture of every grasp, e.g. closed.svh_pinky=0.856 (rad)")
    ap.add_argument("--model", type=Path, help="a trained model: its learned grasp on each of its training "
                                                 "instances instead of the hand-written one (one category)")
    ap.add_argument("--grasp", type=Path, metavar="FILE",
                    help="this grasp file instead of models/grasps/<category>_handwritten.yaml (its category's "
                         "objects only; e.g. one written by catgrasp search-grasp)")
    ap.add_argument("--objects", type=Path, nargs="+", metavar="DIR",
                    help="imported objects (catgrasp import-object; e.g. out/ycb/drill/ycb_035) instead of the "
                         "embedded instances; each in its own category")
    ap.add_argument("--placements", type=int, default=0, metavar="N",
                    help="N seeded random placements per object (seeds 0..N-1) instead of the scenario's pose")
    ap.add_argument("--plan", nargs="+", action="extend", default=[], metavar="FIELD=VALUE",
                    help="a PlanParams field set for every trial (e.g. close_time=1.6; numbers only)")
    ap.add_argument("--mass-scale", type=float, default=None, metavar="S",
                    help="the object's mass (and rotational inertia) times S, e.g. 3: a full bottle")
    ap.add_argument("--no-object-clearance", action="store_true",
                    help="plan without the object clearance (PlanParams.object_penetration_tol=None)")
    args = ap.parse_args(argv)

    variant = {k: list(v) for k, v in (("shift", args.shift), ("rotate", args.rotate)) if v and any(v)}
    if args.yaw:
        variant["yaw"] = args.yaw
    if args.posture:
        variant["postures"] = posture_overrides(args.posture, ap.error)
    instances = {c: list_instances(c) for c in args.categories}
    if args.model is not None:
        from catgrasp_drake.category_model import CategoryModel
        from catgrasp_drake.core.fileio import file_sha256

        if len(args.categories) != 1:
            ap.error("--model: give the model's one category with --categories")
        model = CategoryModel.load(args.model, category=args.categories[0])
        instances = {args.categories[0]: list(model.instances)}
        variant |= {"model": str(args.model), "model_sha256": file_sha256(args.model)}
    if args.no_object_clearance:
        variant["no_object_clearance"] = True
    if args.plan:
        variant["plan"] = plan_overrides(args.plan, ap.error)
    if args.mass_scale is not None:
        if not args.mass_scale > 0:
            ap.error(f"--mass-scale: must be > 0, got {args.mass_scale}")
        variant["mass_scale"] = args.mass_scale
    if args.grasp is not None:
        from catgrasp_drake.core.fileio import file_sha256
        from catgrasp_drake.errors import InputError, ModelFileError
        from catgrasp_drake.station.handwritten import read_grasp_file

        if args.model is not None:
            ap.error("--grasp and --model: a model's learned grasps replace the grasp file")
        if not args.grasp.is_file():
            ap.error(f"--grasp: no such grasp file {args.grasp}")
        try:
            spec = read_grasp_file(args.grasp)
        except (InputError, ModelFileError) as e:
            ap.error(f"--grasp: {e}")
        grasp_category = spec.get("category") if isinstance(spec, dict) else None
        if grasp_category not in CATEGORIES:
            ap.error(f"--grasp: {args.grasp} names no category (drill, spray_bottle, mug)")
        args.categories = [grasp_category]
        variant |= {"grasp_file": str(args.grasp.resolve()), "grasp_sha256": file_sha256(args.grasp)}
    if args.objects:
        if args.model is not None:
            ap.error("--objects and --model: a model's learned grasps are for its own training instances")
        from catgrasp_drake.data.dataset import imported_object

        objects = [(*imported_object(d), str(d)) for d in args.objects]
        others = sorted({c for c, _, _ in objects} - set(args.categories)) if args.grasp is not None else []
        if others:
            ap.error(f"--grasp: a {args.categories[0]} grasp, but --objects holds {', '.join(others)}")
        args.categories = [c for c in CATEGORIES if any(o[0] == c for o in objects)]
        targets = [(c, i, {"model_dir": d}) for c, i, d in objects]
    else:
        targets = [(c, i, {}) for c in args.categories for i in instances[c]
                   if not args.instances or i in args.instances]
    seeds = [{"seed": k} for k in range(args.placements)] or [{}]
    specs = [{"category": c, "instance": i, **where, **seed, **variant} for c, i, where in targets for seed in seeds]

    def progress(outcome, done, total):
        r = outcome.result
        what = "error" if r.get("status") == "error" else ("ok" if r.get("functional") else r.get("reason"))
        cached = " (cached)" if outcome.cached else ""
        seed = f" seed {outcome.spec['seed']}" if "seed" in outcome.spec else ""
        sys.stderr.write(f"[{done}/{total}] {outcome.spec['instance']}{seed}: {what}{cached}\n")

    outcomes = run_tasks(sweep_task, specs, cache_dir=None if args.no_cache else args.cache,
                         code_version=code_version(), workers=args.workers, progress=progress)
    rows = []
    for o in outcomes:
        r = o.result
        rows.append({**o.spec, **r})
    out = sys.stdout
    for c in args.categories:
        sel = [r for r in rows if r["category"] == c]
        if not sel:
            continue
        out.write(f"\n{c}\n{'instance':18s} {'grasp':6s} {'functional':10s} {'reason':26s} {'rise(m)':>8s} "
                  f"{'tilt':>6s} {'F_trig(N)':>9s} {'shift(mm)':>9s} {'turn':>5s} {'moved(mm)':>9s} {'wall(s)':>7s}\n")
        for r in sel:
            if r.get("status") == "error":
                out.write(f"{r['instance']:18s} {'-':6s} {'-':10s} error: {r['error'][:60]}\n")  # noqa: E501
                continue
            name = r["instance"] + (f" #{r['seed']}" if "seed" in r else "")
            out.write(f"{name:18s} {str(r['grasp']):6s} {str(r['functional']):10s} "
                      f"{(r['reason'] or '-'):26s} {r['rise_m']:8.3f} {r['tilt_deg']:6.1f} "
                      f"{_fmt(r.get('trigger_force_N'), 9, 1)} {_fmt(r.get('in_hand_shift_m'), 9, 1, 1000)} "
                      f"{_fmt(r.get('in_hand_turn_deg'), 5, 1)} {_fmt(r.get('object_shift_mm'), 9, 1)} "
                      f"{r['wall_time_s']:7.1f}\n")
        n = len(sel)
        g = sum(bool(r.get("grasp")) for r in sel)
        f = sum(bool(r.get("functional")) for r in sel)
        out.write(f"{c}: grasp {g}/{n} ({100 * g / n:.0f} %), functional {f}/{n} ({100 * f / n:.0f} %)\n")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        from catgrasp_drake.core.fileio import atomic_write_text

        atomic_write_text(args.json, json.dumps(rows, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    from catgrasp_drake.errors import run_script

    raise SystemExit(run_script(main))
