"""``catgrasp`` command line: the project's main jobs.

Progress and results are printed here, never inside the library.

Each subcommand imports the stack it runs inside its handler (pydrake,
open3d, trimesh, ray): ``catgrasp --help`` and a refused argument answer in
a fraction of a second instead of after seconds of imports.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

from catgrasp_drake.errors import CatgraspError, InputError, one_line

# ----------------------------------------------------------------------------- argument checks
# Bad arguments are refused before any work starts, each with one line naming it.


#: Upper bounds that catch typos before hours of simulation (a seed must fit 32 bits).
MAX_SEED, MAX_SAMPLES, MAX_WORKERS = 2**32 - 1, 10_000, 1024


def _int_at_least(low: int, high: int | None = None):
    what = f"an integer >= {low}" if high is None else f"an integer in [{low}, {high}]"

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}") from None
        if value < low or (high is not None and value > high):
            raise argparse.ArgumentTypeError(f"expected {what}, got {value}")
        return value

    parse.__name__ = "integer"
    return parse


def _float_in(low: float, high: float | None = None, *, open_low: bool = False):
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        ok = math.isfinite(value) and (value > low if open_low else value >= low) and (high is None or value <= high)
        if not ok:
            rng = (f"> {low:g}" if open_low else f">= {low:g}") if high is None else f"in [{low:g}, {high:g}]"
            raise argparse.ArgumentTypeError(f"expected a finite number {rng}, got {text!r}")
        return value

    parse.__name__ = "number"
    return parse


def _check_category(category: str) -> list[str]:
    """The category's instance names, or InputError naming the known categories."""
    from catgrasp_drake.data.dataset import list_instances

    return list_instances(category)


def _check_instances(category: str, instances, what: str = "--instances") -> None:
    names = _check_category(category)
    unknown = [n for n in instances or () if n not in names]
    if unknown:
        raise InputError(f"{what}: unknown {category} instance(s) {unknown}; known: {', '.join(names)}")


def _cmd_generate_data(args) -> int:
    from catgrasp_drake.data.dataset import generate_dataset, objects_dir, tree_digest

    if args.check:
        with tempfile.TemporaryDirectory() as tmp:
            generate_dataset(tmp, seed=args.seed)
            fresh, committed = tree_digest(tmp), tree_digest(objects_dir())
        differ = sorted(k for k in fresh.keys() | committed.keys() if fresh.get(k) != committed.get(k))
        if differ:
            print(f"data set differs from seed {args.seed} in {len(differ)} files, e.g. {differ[:5]}")
            return 1
        print(f"data set matches seed {args.seed} byte for byte ({len(fresh)} files)")
        return 0
    out = Path(args.out) if args.out else None
    t0 = time.perf_counter()
    written = generate_dataset(out, seed=args.seed, progress=lambda w: print(f"  {w.name:18s} {w.mass_kg:.3f} kg"))
    print(f"wrote {len(written)} instances to {out or objects_dir()} in {time.perf_counter() - t0:.1f} s")
    return 0


def _cmd_contact_sheet(args) -> int:
    from catgrasp_drake.viz.sheets import dataset_contact_sheet, ycb_contact_sheet

    for category in args.categories or ():
        _check_category(category)
    t0 = time.perf_counter()
    if args.ycb is not None:
        ycb_contact_sheet(args.ycb or None, args.out)
    else:
        dataset_contact_sheet(args.out, categories=args.categories)
    print(f"wrote {args.out} in {time.perf_counter() - t0:.1f} s")
    return 0


def _cmd_clouds(args) -> int:
    from catgrasp_drake.data.cloud_io import write_point_cloud
    from catgrasp_drake.data.dataset import instance_clouds, list_instances

    _check_category(args.category)
    out = Path(args.out)
    names = list_instances(args.category)
    for name, cloud in zip(names, instance_clouds(args.category, names, args.voxel)):
        write_point_cloud(out / f"{name}.{args.format}", cloud)
        print(f"  {name:18s} {len(cloud):5d} points")
    print(f"wrote {args.category} clouds to {out}")
    return 0


def _time_left(seconds: float) -> str:
    """``~40 s``, ``~12 min`` or ``~1 h 30 min``: a progress bar's estimate of the time left."""
    if seconds < 60:
        return f"~{max(int(round(seconds)), 1)} s"
    minutes = int(round(seconds / 60))
    return f"~{minutes} min" if minutes < 60 else f"~{minutes // 60} h {minutes % 60} min"


class _Progress:
    """A one-line progress bar on stderr (CLI only; the library never prints)."""

    def __init__(self):
        self.t0 = time.perf_counter()
        self.stage = None

    def __call__(self, stage: str, done: int, total: int) -> None:
        if stage != self.stage:
            if self.stage is not None:
                sys.stderr.write("\n")
            self.stage, self.t0 = stage, time.perf_counter()
        width = 30
        filled = int(width * done / max(total, 1))
        rate = done / max(time.perf_counter() - self.t0, 1e-9)
        left = f", {_time_left((total - done) / rate)} left" if 0 < done < total else ""
        sys.stderr.write(f"\r  {stage:<7s} [{'#' * filled}{'.' * (width - filled)}] {done}/{total} "
                         f"({rate:.2f}/s{left})   ")
        if done == total:
            sys.stderr.write("\n")
            self.stage = None
        sys.stderr.flush()


def _category_folder(args):
    """The category folder of ``train --objects FOLDER`` (a folder with category.yaml), else None."""
    from catgrasp_drake.data.category_folder import CATEGORY_FILE, read_category_folder

    if len(args.objects or ()) != 1 or not (Path(args.objects[0]) / CATEGORY_FILE).is_file():
        if args.category is None:
            raise InputError("train: give a category (drill, spray_bottle, mug) or --objects FOLDER with a "
                             "category.yaml (a new category)")
        return None
    cat = read_category_folder(args.objects[0])
    if args.category not in (None, cat.name, cat.like):
        raise InputError(f"--objects {args.objects[0]}: a {cat.name!r} category (like {cat.like}), "
                         f"not {args.category!r}")
    for flag, value in (("--instances", args.instances), ("--canonical", args.canonical), ("--stretch", args.stretch),
                        ("--grasp", args.grasp)):
        if value:
            raise InputError(f"{flag}: a category folder trains on its own meshes, canonical instance and grasp")
    return cat


#: ``--height-error`` of ``train --search`` and ``search-grasp`` (grasping.robustness.Robustness.height_m).
HEIGHT_ERROR_HELP = ("the perturbed trials' grasp off in height by up to M metres against the object (uniform; a "
                     "perception error in height; default 0: none, the table fixes the object's height)")


def _cmd_train(args) -> int:
    from catgrasp_drake.grasping.sampling import SamplingParams
    from catgrasp_drake.training import TrainingConfig, train_category

    folder = _category_folder(args)
    if folder is not None:
        args.category = folder.like
    _check_instances(args.category, args.instances)
    if args.instances and len(args.instances) < 2:
        raise InputError(f"--instances: training needs at least 2 instances, got {len(args.instances)}")
    if args.canonical not in (None, "region"):
        _check_instances(args.category, [args.canonical], "--canonical")
        if args.instances and args.canonical not in args.instances:
            raise InputError(f"--canonical: {args.canonical!r} is not among --instances")
    if args.grasp is not None:
        from catgrasp_drake.station.handwritten import read_grasp_file

        if not Path(args.grasp).is_file():
            raise InputError(f"--grasp: no such grasp file {args.grasp}")
        read_grasp_file(args.grasp, args.category)  # a wrong category or bad YAML before any training
    search = None
    if args.search:
        from catgrasp_drake.grasping.robustness import Robustness
        from catgrasp_drake.grasping.search import CemParams
        from catgrasp_drake.training import InstanceSearch

        if args.elite > args.population:
            raise InputError(f"--elite: {args.elite} is more than --population {args.population}")
        search = InstanceSearch(cem=CemParams(rounds=args.rounds, population=args.population, elite=args.elite),
                                robustness=Robustness(perturbations=args.perturbations, seed=args.seed,
                                                      height_m=args.height_error),
                                keep=args.keep)
    config = TrainingConfig(samples_per_instance=args.samples, seed=args.seed, workers=args.workers,
                            canonical_instance=args.canonical, cache_dir=args.cache, ray=args.ray,
                            sampling=SamplingParams(), search=search, grasp_file=args.grasp,
                            regressor=args.regressor or ("trials" if args.search else "ridge"))
    if folder is not None:
        return _train_folder(folder, config, args)
    from catgrasp_drake.data.dataset import list_instances

    instances = args.instances
    if not instances:
        names = list_instances(args.category)
        if not 0 <= args.hold_out <= len(names) - 2:
            raise InputError(f"--hold-out: expected 0..{len(names) - 2} for {len(names)} instances, "
                             f"got {args.hold_out}")
        instances = names[:len(names) - args.hold_out]
        if args.canonical not in (None, "region") and args.canonical not in instances:
            raise InputError(f"--canonical: {args.canonical!r} is held out; lower --hold-out or pick another")
        if args.hold_out:
            print(f"held out (never trained on; the demo's novel instances): {', '.join(names[len(instances):])}")
    how = (f"a robustness search per instance ({args.rounds} rounds x {args.population} candidates x "
           f"{args.perturbations} trials at most)" if args.search else f"{args.samples} sampled motions per instance")
    print(f"training {args.category} on {len(instances)} instances: {how}, seed {args.seed}"
          + (f", canonical grasp {args.grasp}" if args.grasp else ""))
    objects = list(args.objects or ())
    if objects:
        print(f"and {len(objects)} imported objects: {', '.join(str(d) for d in objects)}")
    if args.stretch:
        from catgrasp_drake.benchmark.runner import stretched_objects

        stretched = stretched_objects(args.stretch_dir, args.category, instances, args.stretch)
        print(f"and their {len(stretched)} stretched copies ({', '.join(args.stretch)}) under "
              f"{Path(args.stretch_dir) / args.category}")
        objects += [directory for _, directory in stretched]
    model = train_category(args.category, instances, config, objects=objects, progress=_Progress())
    out = Path(args.out or f"models/trained/{args.category}.npz")
    model.save(out)
    _print_training(model)
    print(f"wrote {out}")
    return 0


def _train_folder(folder, config, args) -> int:
    from catgrasp_drake.training import train_category_folder
    from catgrasp_drake.viz.sheets import import_sheet

    print(f"new category {folder.name!r} (like {folder.like}) from {folder.folder}: {len(folder.meshes)} meshes, "
          f"canonical {folder.canonical.name}, grasp {folder.grasp.name}")
    model, imported = train_category_folder(folder.folder, config, progress=_Progress())
    for obj in imported:
        region = obj.regions.get(next(iter(obj.regions), ""), {})
        png = import_sheet(obj.directory, reference_dir=imported[0].directory)
        print(f"  imported {obj.name:<14s} {obj.mass_kg:.3f} kg, {next(iter(obj.regions), 'no region')} at "
              f"{region.get('center')} -> {obj.directory} (check {png.name})")
    out = Path(args.out or imported[0].directory.parent / f"{folder.name}.npz")
    model.save(out)
    _print_training(model)
    print(f"wrote {out} (a {folder.like} model: catgrasp demo --object {imported[-1].directory} --model {out})")
    return 0


def _print_training(model) -> None:
    st = model.stats
    print(f"{'instance':<18s} {'sampled':>7s} {'constr.':>7s} {'plan':>5s} {'sim':>4s} {'grasp':>5s} {'func.':>5s}")
    for name, s in st["per_instance"].items():
        print(f"{name:<18s} {s['sampled']:7d} {s['rejected_constraint']:7d} {s['rejected_plan']:5d} "
              f"{s['simulated']:4d} {s['grasped']:5d} {s['functional']:5d}")
    if "canonical_choice" in st:
        errs = st["canonical_choice"]["errors_mm"]
        print(f"canonical instance: {model.canonical_instance}, by {st['canonical_choice']['by']}: "
              + ", ".join(f"{n} {e:.1f}" for n, e in sorted(errs.items(), key=lambda kv: kv[1])))
    rate = st["trials_functional"] / max(st["trials_simulated"], 1)
    print(f"simulated trials: {st['trials_simulated']}, functional successes: {st['trials_functional']} "
          f"({100 * rate:.0f} %), instances with a functional success: "
          f"{st['instances_with_functional_success']}/{st['instances']}")
    _print_regression(st["regression"])
    print(f"latent dimensions q = {st['q']}; time: shape space {st['shape_time_s']} s, trials "
          f"{st['trial_time_s']} s ({st['trials_per_s']} trials/s), total {st['total_time_s']} s")


def _print_regression(reg: dict) -> None:
    """How a model's regressor was chosen (``stats["regression"]``), in one or two lines."""
    loo = reg.get("by_loo_error", reg)
    if "trial_score_by_candidate" in reg:
        print(f"regressor: {reg['regressor']} {reg['hyperparameters']}, chosen by {reg['trials']} leave-one-"
              f"instance-out grasp trials (mean robustness by candidate: {reg['trial_score_by_candidate']})")
    if "loo_error_mm" in loo:
        print(f"{'by' if 'trial_score_by_candidate' in reg else 'regressor:'} leave-one-instance-out error at the "
              f"functional point: {loo['regressor']} {loo['hyperparameters']} {loo['loo_error_mm']} mm (by family: "
              f"{loo['loo_error_mm_by_family']})")
    elif "trial_score_by_candidate" not in reg:
        print(f"regressor: {reg['regressor']}")


def _cmd_refit(args) -> int:
    from catgrasp_drake.category_model import CategoryModel
    from catgrasp_drake.training import TrainingConfig, refit_regressor

    path = Path(args.model or f"models/trained/{args.category}.npz")
    model = CategoryModel.load(path, category=args.category)
    config = TrainingConfig(regressor=args.regressor, workers=args.workers, cache_dir=args.cache, ray=args.ray)
    print(f"refitting the {args.category} regressor of {path} ({len(model.instances)} training instances): "
          f"{args.regressor}")
    model = refit_regressor(model, config, progress=_Progress())
    out = Path(args.out or path)
    model.save(out)
    _print_regression(model.stats["regression"])
    print(f"wrote {out}")
    return 0


def _cmd_evaluate(args) -> int:
    from catgrasp_drake.evaluation import EvalConfig, evaluate, format_table, leave_two_out

    _check_instances(args.category, args.instances)
    folds = leave_two_out(args.category, args.folds)  # InputError for a bad --folds
    if args.instances:
        tested = {n for _, test in folds for n in test}
        if not set(args.instances) & tested:
            raise InputError(f"--instances: {args.instances} are not test instances of any fold; "
                             f"test instances: {', '.join(sorted(tested))}")
    config = EvalConfig(category=args.category, methods=tuple(args.methods), views=tuple(args.views),
                        seed=args.seed, folds=args.folds, instances=tuple(args.instances) if args.instances else None,
                        samples_per_instance=args.samples, workers=args.workers, out_dir=args.out, ray=args.ray)
    print(f"evaluating {args.category}: leave-two-out, methods {', '.join(config.methods)}, "
          f"views {', '.join(config.views)}, seed {args.seed}")
    report = evaluate(config, progress=_Progress())
    print(format_table(args.category, report.table))
    for m, t in report.inference_s.items():
        print(f"inference time {m:<8s} median {t['median']:.2f} s, max {t['max']:.2f} s")
    c = report.confidence
    if c.get("auroc") is not None:
        print(f"confidence (latent): AUROC {c['auroc']:.2f} over {c['trials']} trials; functional success "
              f"{100 * c['success_all']:.0f} % -> {100 * c['success_kept']:.0f} % when the least confident 20 % "
              f"are refused (threshold {c['threshold']:.2f})")
    out = Path(args.out) / args.category
    print(f"wrote {out / 'records.jsonl'} and {out / 'report.json'} in {report.wall_s:.0f} s")
    return 0


def _default_records_path(config) -> Path:
    from catgrasp_drake.benchmark.runner import CATEGORIES

    if config.split == "objects":  # the user's own objects: not the committed tables' records
        return Path("out/benchmark") / ("objects" + ("_" + "+".join(config.views) if tuple(config.views) != ("single",)
                                                     else "") + ".jsonl")
    parts = [config.split if config.split != "fresh" else f"fresh_seed{config.data_seed}"]
    if config.split != "smoke" and tuple(config.categories) != CATEGORIES:
        parts.append("+".join(config.categories))
    if tuple(config.views) != ("single",):
        parts.append("+".join(config.views))
    if config.physics != "default":
        parts.append(config.physics)
    return Path("benchmarks/results") / ("_".join(parts) + ".jsonl")


def _cmd_benchmark(args) -> int:
    from catgrasp_drake.benchmark.report import (
        load_benchmark_records,
        merged_records,
        summary_table,
        write_benchmark_records,
    )
    from catgrasp_drake.benchmark.runner import BenchmarkConfig, run_benchmark, trial_specs

    split = args.split or ("objects" if args.objects else "test")
    if args.objects and split != "objects":
        raise InputError(f"--objects: the imported objects are the split 'objects', not {split!r}")
    config = BenchmarkConfig(
        split=split, objects=tuple(args.objects or ()), categories=tuple(args.categories), methods=tuple(args.methods),
        views=tuple(args.views),
        placements=args.placements, instances_per_category=args.instances_per_category,
        instances=tuple(args.instances) if args.instances else None, data_seed=args.data_seed, seed=args.seed,
        noise=not args.no_noise,
        physics=args.physics, min_confidence=args.min_confidence, data_dir=args.data, cache_dir=args.cache,
        workers=args.workers, ray=args.ray)
    model_paths = None
    if args.model:  # a user's model (e.g. a category folder's) for their own objects, never the committed tables
        from catgrasp_drake.category_model import CategoryModel

        if split not in ("objects", "stress", "val"):
            raise InputError(f"--model: only with --objects or a tuning split, stress or val (the split {split!r} "
                             "is measured with the committed models)")
        model_paths = {CategoryModel.load(args.model).category: str(args.model)}
        if not args.out and split in ("stress", "val"):
            raise InputError(f"--model with --split {split}: give --out (benchmarks/results/ holds the committed "
                             "models' records)")
    out = Path(args.out) if args.out else _default_records_path(config)
    kept = load_benchmark_records(out) if args.merge and out.exists() else []  # read (and checked) before the run
    specs = trial_specs(config, model_paths=model_paths)
    if not specs:
        raise InputError("the selection holds no trials (check --instances and --categories)")
    objects = sorted({(s["category"], s["instance"]) for s in specs})
    print(f"benchmark: split {config.split}, {len(specs)} trials ({len(objects)} objects of "
          f"{', '.join(sorted({c for c, _ in objects}))}; methods {', '.join(config.methods)}; views "
          f"{', '.join(config.views)}; {len({s['trial'] for s in specs})} placements each; physics {config.physics}; "
          f"depth noise {'on' if config.noise else 'off'})")
    bar = _Progress()
    t0 = time.perf_counter()
    records = run_benchmark(config, model_paths=model_paths, progress=lambda o, done, total: bar("trials", done, total))
    written = merged_records(kept, records) if args.merge else records
    write_benchmark_records(out, written)
    errors = [r for r in records if r.get("reason") in ("task_error", "worker_died")]
    print(summary_table(records, tuning=True))
    if errors:
        print(f"{len(errors)} trials ended in an error (reason task_error/worker_died), e.g.: {errors[0]['detail']}")
    merged = f"; {len(written) - len(records)} records of other trials kept from the file" if args.merge else ""
    print(f"wrote {out} ({len(written)} records{merged}) in {time.perf_counter() - t0:.0f} s")
    return 0


def _cmd_report(args) -> int:
    from catgrasp_drake.benchmark.report import (
        benchmark_tables,
        check_markdown,
        committed_models,
        load_benchmark_records,
        report,
    )

    paths = args.records or sorted(str(p) for p in Path("benchmarks/results").glob("*.jsonl"))
    if not paths:
        raise InputError("no records: pass --records FILE... or run 'catgrasp benchmark' first")
    models = committed_models()  # rows of other models are marked
    if args.print:
        print(benchmark_tables(load_benchmark_records(paths), committed=models), end="")
        return 0
    if args.check:
        records = load_benchmark_records(paths)
        stale = {md: check_markdown(md, records, models) for md in args.markdown}
        stale = {md: m for md, m in stale.items() if m}
        for md, markers in stale.items():
            print(f"{md}: out of date: {', '.join(markers)} (run 'catgrasp report')")
        if not stale:
            print(f"{', '.join(args.markdown)}: tables match {len(records)} records")
        return 1 if stale else 0
    written = report(paths, args.markdown, committed=models)
    print(f"rebuilt the benchmark tables of {', '.join(map(str, written))} from {len(paths)} record files")
    return 0


def _cmd_demo(args) -> int:
    from catgrasp_drake.demo import run_demo

    return run_demo(args)


def _cmd_import_object(args) -> int:
    from catgrasp_drake.data.dataset import CATEGORIES
    from catgrasp_drake.data.importer import LOW_CONFIDENCE, import_object, parse_transform
    from catgrasp_drake.data.meshes import MIN_TIPPING_ANGLE_DEG
    from catgrasp_drake.errors import ModelFileError

    if args.category not in CATEGORIES:
        raise InputError(f"--category: unknown category {args.category!r}; known: {', '.join(CATEGORIES)}")
    transform = parse_transform(args.transform) if args.transform is not None else None
    region = None
    if args.region is not None:
        name, *xyz = args.region
        try:
            point = [float(v) for v in xyz]
        except ValueError:
            point = [math.nan]
        if not all(math.isfinite(v) for v in point):
            raise InputError(f"--region: expected NAME X Y Z (metres, the file's frame), got {' '.join(args.region)!r}")
        region = (name, point)
    model = None
    if transform is None or region is None:  # the automatic alignment or the region transfer needs the model
        from catgrasp_drake.category_model import CategoryModel
        from catgrasp_drake.demo import default_model_path

        path = Path(args.model) if args.model else default_model_path(args.category)
        if not path.is_file():
            raise ModelFileError(f"{path}: no trained {args.category} model; run 'catgrasp train {args.category}' "
                                 "or pass --model")
        model = CategoryModel.load(path, category=args.category)
    t0 = time.perf_counter()
    imported = import_object(args.path, args.category, model=model, mass_kg=args.mass, region=region,
                             transform=transform, out=args.out, name=args.name)
    t_import = time.perf_counter() - t0
    rec, fit = imported.record, imported.alignment.fit
    tf = rec["transform"]
    rpy, xyz = " ".join(f"{v:.3f}" for v in tf["rpy_deg"]), " ".join(f"{v:.5f}" for v in tf["xyz_m"])
    how = (f"automatic (fit confidence {fit['confidence']:.2f}, scale {fit['scale']:.3f}, {fit['starts']} starts, "
           f"{fit['seconds']:.1f} s)" if tf["automatic"] else "stated (--transform)")
    print(f"{imported.name}: {rec['source'].get('kind', 'mesh')} {args.path} -> {imported.category}")
    print(f"  alignment  {how}: rpy {rpy} deg, xyz {xyz} m (canonical <- file; --transform \"{rpy} {xyz}\" "
          "repeats it)")
    for name, r in imported.regions.items():
        print(f"  region     {name}: centre {' '.join(f'{v:.3f}' for v in r['center'])} m, half-extents "
              f"{' '.join(f'{v:.3f}' for v in r['half_extents'])} m ({rec['region_source']})")
    if not imported.regions:
        print("  region     none")
    print(f"  mass       {imported.mass_kg:.3f} kg ({rec['mass_source']}); collision mesh: {rec['collision_mesh']}")
    margin_mm = 1000 * rec["support_margin_m"]
    tips = (f"; it tips at {rec['tipping_angle_deg']:.1f} deg (below {MIN_TIPPING_ANGLE_DEG:g}: it falls over by "
            "itself in simulation)") if margin_mm > 0 else ""
    print(f"  stands     {'yes' if rec['stands'] else 'NO'}: its centre of mass is {abs(margin_mm):.0f} mm "
          f"{'inside' if margin_mm > 0 else 'outside'} its base{tips}")
    try:
        from catgrasp_drake.planning.fit import hand_fit
        from catgrasp_drake.station.handwritten import handwritten_trial

        hand = hand_fit(*handwritten_trial(object_dir=imported.directory, grasp_file=args.grasp))
        which = f"grasp {Path(args.grasp).name}" if args.grasp else f"{imported.category} hand-written grasp"
        print(f"  hand fit   the {which} on its region: {hand.summary()}")
    except InputError as e:  # e.g. no region the category's grasp is anchored on
        hand = None
        print(f"  hand fit   not checked: {e}")
    t0 = time.perf_counter()
    from catgrasp_drake.viz.sheets import import_sheet

    folder_canonical = ((model.params.get("objects") or {}).get(model.canonical_instance)
                        if model is not None else None)  # a category folder's model: its own canonical
    png = import_sheet(imported.directory, reference_dir=folder_canonical)
    print(f"wrote {imported.directory}/ ({imported.name}.obj, {imported.name}.sdf, annotations.json) and {png} "
          f"in {t_import + time.perf_counter() - t0:.1f} s")
    if not rec["stands"]:
        print("warning: it falls over by itself on the table, so no grasp from the table can be tested on it "
              "(a corded drill without a battery base?); check the alignment's up direction", file=sys.stderr)
    if imported.confidence is not None and imported.confidence < LOW_CONFIDENCE:
        print(f"warning: the fit's confidence {imported.confidence:.2f} is below {LOW_CONFIDENCE}: check {png} "
              "and pass --transform if the alignment is wrong", file=sys.stderr)
    if hand is not None and not hand.plannable:
        grasp = "the grasp" if args.grasp else "the category's grasp"
        print(f"warning: {grasp} does not fit it (the preshaped hand lies inside it wherever the planner "
              "may move it): expect collision_before_closing", file=sys.stderr)
    print(f"use it: catgrasp demo --object {imported.directory}" + (f" --model {args.model}" if args.model else ""))
    return 0


def _cmd_film(args) -> int:
    if args.record:
        from catgrasp_drake.benchmark.report import load_benchmark_records
        from catgrasp_drake.benchmark.runner import film_benchmark_trial
        from catgrasp_drake.film import verdict_word

        records = load_benchmark_records([args.record])
        if not 0 <= args.index < len(records):
            raise InputError(f"--index: {args.index} is not a record of {args.record} (it holds {len(records)})")
        record = records[args.index]
        out = Path(args.out or f"out/film/{record['instance']}_t{record['trial']}_{record['method']}.png")
        result, spec = film_benchmark_trial(record, out, data_dir=args.data,
                                            objects=[args.object] if args.object else (), closeup=args.closeup,
                                            size=tuple(args.size) if args.size else None)
        then = verdict_word(record["grasp"], record["functional"])
        now = verdict_word(result.grasp_success, result.functional_success)
        same = "" if (then, spec["model_sha256"]) == (now, record["model_sha256"]) else (
            f" -- the record says {then}" + (" (its model file has changed since)"
                                               if spec["model_sha256"] != record["model_sha256"] else ""))
        print(f"wrote {out}: {now} ({result.failure_reason or 'ok'}){same}")
        return 0
    from catgrasp_drake.film import film_grasp, verdict_word
    from catgrasp_drake.station.handwritten import handwritten_trial

    instance = None
    if not args.object:
        if not args.category:
            raise InputError("give --category (with --instance) or --object DIR or --record FILE")
        instance = args.instance or _check_category(args.category)[0]
        _check_instances(args.category, [instance], "--instance")
    scenario, motion = handwritten_trial(args.category, instance, object_dir=args.object, seed=args.seed,
                                         shift_O=args.shift, grasp_file=args.grasp)
    instance = scenario.object.instance
    out = Path(args.out or f"out/film/{instance}_handwritten.png")
    result = film_grasp(scenario, motion, out, closeup=args.closeup, size=tuple(args.size) if args.size else None)
    detail = f": {result.detail}" if result.detail else ""
    print(f"wrote {out}: {verdict_word(result.grasp_success, result.functional_success)} "
          f"({result.failure_reason or 'ok'}{detail})")
    return 0


def _cmd_search_grasp(args) -> int:
    import json

    import yaml

    from catgrasp_drake.core.fileio import atomic_write_text
    from catgrasp_drake.data.dataset import imported_object
    from catgrasp_drake.grasp_search import apply_variation_to_spec, search_grasp
    from catgrasp_drake.grasping.robustness import Robustness
    from catgrasp_drake.grasping.search import CemParams
    from catgrasp_drake.robot.models import load_hand_postures
    from catgrasp_drake.station.handwritten import GRASPS_DIR, read_grasp_file
    from catgrasp_drake.station.variation import VARIATION_NAMES, VARIATION_SCALE

    instances = _check_category(args.category)
    object_dirs = {}
    for directory in args.objects or ():
        category, name = imported_object(directory)
        if category != args.category:
            raise InputError(f"--objects: {directory} is a {category}, not a {args.category}")
        if name in object_dirs or name in instances:
            raise InputError(f"--objects: {directory}: the name {name!r} is already taken; re-import it with --name")
        object_dirs[name] = directory
    chosen = args.instances or ([] if object_dirs else instances[::2])
    _check_instances(args.category, chosen)
    chosen = [*chosen, *object_dirs]
    std = VARIATION_SCALE.copy()
    for name in args.freeze or ():
        if name not in VARIATION_NAMES:
            raise InputError(f"--freeze: unknown parameter {name!r}; known: {', '.join(VARIATION_NAMES)}")
        std[VARIATION_NAMES.index(name)] = 0.0
    screen = {}
    for item in args.screen or ():
        if Path(item).is_dir():
            category, name = imported_object(item)
            if category != args.category:
                raise InputError(f"--screen: {item} is a {category}, not a {args.category}")
            screen[name] = item
        else:
            _check_instances(args.category, [item], "--screen")
            screen[item] = None
    grasp_file = Path(args.grasp) if args.grasp else GRASPS_DIR / f"{args.category}_handwritten.yaml"
    if not grasp_file.is_file():
        raise InputError(f"--grasp: no such grasp file {grasp_file}")
    spec = read_grasp_file(grasp_file, args.category)
    bar = _Progress()
    total = args.rounds
    best = [-float("inf")]  # over every round so far (each round's own best can be lower than an earlier one)

    def progress(k, X, scores):
        best[0] = max(best[0], *map(float, scores))
        bar(f"rounds (best so far {best[0]:.2f}, this round {max(map(float, scores)):.2f})", k + 1, total)

    result = search_grasp(args.category, chosen, cem=CemParams(rounds=args.rounds, population=args.population,
                                                                 elite=args.elite, seed=args.seed),
                          robustness=Robustness(perturbations=args.perturbations, seed=args.seed,
                                                mass_scale=tuple(args.mass_scale), height_m=args.height_error),
                          search_std=std,
                          grasp_file=args.grasp, object_dirs=object_dirs, cache_dir=args.cache, workers=args.workers,
                          ray=args.ray, screen=screen, screen_max_refused=args.screen_max_refused,
                          progress=progress)
    out = Path(args.out or f"out/grasp_search/{args.category}")
    new = apply_variation_to_spec(spec, result.best, args.category, load_hand_postures(spec.get("postures",
                                                                                                args.category)))
    atomic_write_text(out / "search.json", json.dumps(result.to_dict(), indent=1) + "\n")
    header = (f"# Searched by `catgrasp search-grasp --category {args.category} --perturbations {args.perturbations} "
              f"--mass-scale {args.mass_scale[0]:g} {args.mass_scale[1]:g}"
              + (f" --height-error {args.height_error:g}" if args.height_error else "")
              + (f" --screen <{len(screen)} objects> --screen-max-refused {args.screen_max_refused}" if screen else "")
              + f"` from {grasp_file.name}: robustness "
              f"{result.start_score:.2f} -> {result.best_score:.2f} on {len(chosen)} instances ({', '.join(chosen)}), "
              f"{result.trials} trials.\n")
    atomic_write_text(out / grasp_file.name, header + yaml.safe_dump(new, sort_keys=False, default_flow_style=None))
    print(f"robustness {result.start_score:.2f} (as written) -> {result.best_score:.2f}; best variation "
          f"{ {k: v for k, v in result.best.items() if v} }; {result.trials} trials in {result.wall_s:.0f} s")
    if result.screened:
        print("screen: candidates drawn / refused per round: "
              + ", ".join(f"{d['drawn']}/{d['infeasible']}" for d in result.screened))
    print(f"wrote {out / 'search.json'} and {out / grasp_file.name} (review, then copy over {grasp_file})")
    return 0


def _cmd_view(args) -> int:
    from catgrasp_drake.category_model import CategoryModel
    from catgrasp_drake.data.dataset import CATEGORIES
    from catgrasp_drake.errors import InputError, ModelFileError
    from catgrasp_drake.viz.meshcat_tools import start_meshcat
    from catgrasp_drake.viz.shape_viewer import ShapeViewer

    if args.category not in CATEGORIES:
        raise InputError(f"unknown category {args.category!r}; known: {', '.join(CATEGORIES)}")
    path = Path(args.model or f"models/trained/{args.category}.npz")
    if not path.is_file():
        raise ModelFileError(f"{path}: no trained model; run 'catgrasp train {args.category}' or pass --model")
    model = CategoryModel.load(path, category=args.category)
    meshcat = start_meshcat()
    viewer = ShapeViewer(model, meshcat)
    if args.html:
        viewer.export_html(args.html)
        print(f"wrote {args.html}")
    print(f"{args.category}: q = {model.space.q} latent sliders, {len(model.instances)} training instances; "
          f"Meshcat at {meshcat.web_url()}")
    if args.once:
        return 0
    print("move the sliders in the browser; Ctrl-C to stop")
    try:
        while True:
            viewer.poll()
            time.sleep(0.05)
    except KeyboardInterrupt:
        print()
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="catgrasp", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)

    g = sub.add_parser("generate-data", help="regenerate the embedded object data set from its seed")
    g.add_argument("--out", help="output directory (default: the repository's models/objects)")
    g.add_argument("--seed", type=_int_at_least(0, MAX_SEED), default=2018)
    g.add_argument("--check", action="store_true", help="only verify the committed data set byte for byte")
    g.set_defaults(func=_cmd_generate_data)

    c = sub.add_parser("contact-sheet", help="render every instance into one PNG")
    c.add_argument("--out", default="docs/objects.png")
    c.add_argument("--categories", nargs="+", default=None)
    c.add_argument("--ycb", nargs="?", const="", default=None, metavar="ROOT",
                   help="instead: the aligned YCB objects next to their reference instances (ROOT: where "
                        "`python -m catgrasp_drake.data.ycb --out ROOT` wrote them; default out/ycb)")
    c.set_defaults(func=_cmd_contact_sheet)

    k = sub.add_parser("clouds", help="full (ray-cast + voxel grid) clouds of a category's instances")
    k.add_argument("category")
    k.add_argument("--out", default="out/clouds")
    k.add_argument("--voxel", type=_float_in(0.0, open_low=True), default=0.01)
    k.add_argument("--format", choices=("npy", "pcd", "ply"), default="pcd")
    k.set_defaults(func=_cmd_clouds)

    t = sub.add_parser("train", help="build a category model (shape space + grasp regressor) by simulated trials")
    t.add_argument("category", nargs="?", default=None,
                   help="drill, spray_bottle or mug (optional with --objects FOLDER: a new category)")
    t.add_argument("--instances", nargs="+", help="training instances (default: all embedded ones but --hold-out)")
    t.add_argument("--hold-out", type=_int_at_least(0), default=2,
                   help="leave the category's last N instances out of training (default 2: the demo's novel ones)")
    t.add_argument("--canonical", help="canonical instance (default: the first training instance); 'region': the "
                   "instance whose trigger/handle the CPD fields carry best onto the others (one shape space each)")
    t.add_argument("--objects", nargs="+", metavar="DIR", default=(),
                   help="imported objects (catgrasp import-object) of the category to train on as well; or ONE "
                        "category folder (meshes + category.yaml, docs/import.md): a new category, trained on its "
                        "meshes alone, written to out/categories/<name>/<name>.npz")
    t.add_argument("--stretch", nargs="+", choices=("small", "large", "thin", "deep"), default=None,
                   metavar="FAMILY",
                   help="also train on each training instance stretched as the stress split's FAMILY (small, "
                        "large, thin, deep; data/stretch.py), written once under --stretch-dir")
    t.add_argument("--stretch-dir", default="out/benchmark/data/stress",
                   help="--stretch: where the stretched copies are written (default: the stress split's own)")
    t.add_argument("--grasp", default=None, metavar="FILE",
                   help="the canonical grasp to train from (default: models/grasps/<category>_handwritten.yaml), "
                        "e.g. a file written by catgrasp search-grasp; the model keeps it as its template")
    t.add_argument("--samples", type=_int_at_least(1, MAX_SAMPLES), default=12, help="sampled motions per instance")
    t.add_argument("--seed", type=_int_at_least(0, MAX_SEED), default=0)
    t.add_argument("--workers", type=_int_at_least(0, MAX_WORKERS), default=None,
                   help="worker processes (default: all cores; 0: in this process)")
    t.add_argument("--cache", default="out/trial_cache", help="trial cache directory (resumes interrupted runs)")
    t.add_argument("--out", help="model file (default: models/trained/<category>.npz)")
    t.add_argument("--ray", default=None,
                   help="run trials on a Ray cluster: 'auto', 'local' or the head's address (extra .[cluster])")
    t.add_argument("--search", action="store_true",
                   help="search each instance's grasp for robustness (cross-entropy) instead of --samples random ones")
    t.add_argument("--rounds", type=_int_at_least(1, 50), default=3, help="--search: rounds")
    t.add_argument("--population", type=_int_at_least(2, 200), default=8, help="--search: candidates per round")
    t.add_argument("--elite", type=_int_at_least(1, 200), default=2, help="--search: elite per round")
    t.add_argument("--perturbations", type=_int_at_least(1, 50), default=2,
                   help="--search: trials per candidate (the first nominal, the others perturbed)")
    t.add_argument("--keep", type=_int_at_least(1, 50), default=3, help="--search: best grasps kept per instance")
    t.add_argument("--height-error", type=float, default=0.0, metavar="M",
                   help="--search: " + HEIGHT_ERROR_HELP)
    t.add_argument("--regressor", choices=("ridge", "auto", "trials"), default=None,
                   help="latent -> grasp regressor: ridge; auto: chosen by leave-one-instance-out error at the "
                        "functional point; trials: by leave-one-instance-out grasp trials, the canonical grasp "
                        "among the candidates (default: trials with --search, ridge without)")
    t.set_defaults(func=_cmd_train)

    r = sub.add_parser("refit", help="choose and fit a trained model's latent -> grasp regressor again from its "
                                     "stored training set (no grasp search)")
    r.add_argument("category")
    r.add_argument("--model", help="model file (default: models/trained/<category>.npz)")
    r.add_argument("--regressor", choices=("ridge", "auto", "trials"), default="trials",
                   help="how to choose (see train --regressor; default: trials)")
    r.add_argument("--out", help="where to write the refitted model (default: over --model)")
    r.add_argument("--workers", type=_int_at_least(0, MAX_WORKERS), default=None,
                   help="worker processes for the trials (default: all cores; 0: in this process)")
    r.add_argument("--cache", default="out/trial_cache", help="trial cache directory (resumes interrupted runs)")
    r.add_argument("--ray", default=None,
                   help="run trials on a Ray cluster: 'auto', 'local' or the head's address (extra .[cluster])")
    r.set_defaults(func=_cmd_refit)

    e = sub.add_parser("evaluate", help="the paper's Table I: leave-two-out, full and single views, baselines")
    e.add_argument("category")
    e.add_argument("--methods", nargs="+", default=["latent", "rigid", "cpd", "nearest"],
                   choices=["latent", "rigid", "cpd", "nearest"])
    e.add_argument("--views", nargs="+", default=["full", "single"], choices=["full", "single"])
    e.add_argument("--seed", type=_int_at_least(0, MAX_SEED), default=0, help="seed of every test object's placement")
    e.add_argument("--folds", type=_int_at_least(1), default=None,
                   help="number of leave-two-out folds (default: the paper's)")
    e.add_argument("--instances", nargs="+", help="only these test instances (their folds' models only)")
    e.add_argument("--samples", type=_int_at_least(1, MAX_SAMPLES), default=12,
                   help="sampled motions per instance when training fold models")
    e.add_argument("--workers", type=_int_at_least(0, MAX_WORKERS), default=None,
                   help="worker processes (default: all cores; 0: in this process)")
    e.add_argument("--out", default="out/eval", help="output folder (fold models, trial cache, records, report)")
    e.add_argument("--ray", default=None,
                   help="run trials on a Ray cluster: 'auto', 'local' or the head's address (extra .[cluster])")
    e.set_defaults(func=_cmd_evaluate)

    b = sub.add_parser("benchmark", help="the project's measure: held-out objects, every method through the "
                       "transfer diagram, varied placements, the strict judge, intervals")
    b.add_argument("--split", choices=("test", "fresh", "val", "ycb", "ais", "stress", "smoke", "objects"),
                   default=None,
                   help="test (default): generated from the fixed test seed; fresh: generated from --data-seed "
                        "(instances nobody has seen); val: generated from the fixed validation seed (novel "
                        "draws, a TUNING set); ycb: real scans (extra .[ycb]); "
                        "ais: the 11 real AIS drill clouds (../shared/datasets/ais_drills); stress: the "
                        "committed instances stretched to real proportions (a TUNING set); "
                        "smoke: 2 drills; objects: the --objects")
    b.add_argument("--model", default=None, metavar="FILE",
                   help="with --objects: the model of their category to use (e.g. a category folder's, "
                        "out/categories/<name>/<name>.npz; default: the committed one); with --split stress or val: a "
                        "model to tune (needs --out)")
    b.add_argument("--objects", nargs="+", metavar="DIR", default=None,
                   help="imported objects' directories (catgrasp import-object): the split 'objects'; records go "
                        "to out/benchmark/objects.jsonl")
    b.add_argument("--categories", nargs="+", default=["drill", "spray_bottle", "mug"],
                   choices=["drill", "spray_bottle", "mug"])
    # (literals: the CLI imports no stack at parse time; a test checks them against BENCHMARK_METHODS, METHODS)
    b.add_argument("--methods", nargs="+", default=["latent", "latent_map", "paper", "nearest", "rigid", "cpd"],
                   choices=["latent", "latent_map", "latent_fast", "latent_plain", "paper", "nearest", "rigid",
                            "cpd", "true_object"])
    b.add_argument("--views", nargs="+", default=["single"], choices=["single", "active", "two", "three", "full"],
                   help="single (the measure), active (another camera's view while the views so far leave the "
                        "yaw open, at most 3), two / three (always that many), full (4 cameras)")
    b.add_argument("--placements", type=_int_at_least(1, 1000), default=3, help="placements per instance and view")
    b.add_argument("--instances-per-category", type=_int_at_least(1), default=12)
    b.add_argument("--instances", nargs="+", help="only these instances of the split")
    b.add_argument("--data-seed", type=int, default=None, metavar="N",
                   help="with --split fresh: the data-set seed its instances are generated from (any but the test "
                        "split's and the committed data set's)")
    b.add_argument("--seed", type=_int_at_least(0, MAX_SEED), default=0, help="seed of placements, cameras and noise")
    b.add_argument("--no-noise", action="store_true", help="no depth noise (on by default: Kinect-v2-like)")
    b.add_argument("--physics", choices=("default", "time_step_1e-3", "effort_1.0x", "friction_0.5"),
                   default="default",
                   help="physics-sensitivity setting")
    b.add_argument("--min-confidence", type=_float_in(0.0, 1.0), default=0.0,
                   help="refuse grasps below this estimate confidence (as catgrasp demo)")
    b.add_argument("--data", default="out/benchmark/data", help="where the test split / YCB objects are generated")
    b.add_argument("--cache", default="out/benchmark/cache", help="trial cache (resumes interrupted runs)")
    b.add_argument("--workers", type=_int_at_least(0, MAX_WORKERS), default=None,
                   help="worker processes (default: all cores; 0: in this process)")
    b.add_argument("--ray", default=None, help="run trials on a Ray cluster: 'auto', 'local' or the head's address")
    b.add_argument("--out", help="records file (default: benchmarks/results/<split>[_...].jsonl)")
    b.add_argument("--merge", action="store_true",
                   help="keep the records file's other trials: this run's trials replace theirs (e.g. one category "
                        "re-run after retraining it); without it the file is overwritten")
    b.set_defaults(func=_cmd_benchmark)

    r = sub.add_parser("report", help="rebuild the README's and docs/benchmark.md's benchmark tables from records")
    r.add_argument("--records", nargs="+", help="records files (default: benchmarks/results/*.jsonl)")
    r.add_argument("--markdown", nargs="+", default=["README.md", "docs/benchmark.md"])
    only = r.add_mutually_exclusive_group()
    only.add_argument("--check", action="store_true", help="only check that the tables match the records")
    only.add_argument("--print", action="store_true",
                   help="print every table of the records to stdout instead (e.g. one experiment's file; no file "
                        "is written)")
    r.set_defaults(func=_cmd_report)

    d = sub.add_parser("demo", help="the main job on the embedded default data")
    d.add_argument("--category", default=None, help="drill, spray_bottle or mug (default: drill, or the --object's)")
    d.add_argument("--instance", default=None, help="object instance (default: the last one the model never saw)")
    d.add_argument("--object", default=None, metavar="DIR",
                   help="an imported object's directory (catgrasp import-object) instead of an embedded instance")
    d.add_argument("--seed", type=_int_at_least(0, MAX_SEED), default=0, help="seed of the object's random placement")
    d.add_argument("--view", choices=("single", "active", "two", "three", "full"), default="single",
                   help="one depth camera; active: and another while the views so far leave the object's yaw "
                        "open (at most 3); two / three: that many always; full: four around the object")
    d.add_argument("--model", help="category model file (default: models/trained/<category>.npz)")
    d.add_argument("--min-confidence", type=_float_in(0.0, 1.0), default=0.0,
                   help="refuse the grasp below this estimate confidence (0..1)")
    d.add_argument("--no-meshcat", action="store_true", help="no Meshcat server and no HTML recording")
    d.add_argument("--out", default="out/demo")
    d.set_defaults(func=_cmd_demo)

    i = sub.add_parser("import-object", help="import your own mesh or point cloud as an instance of a category "
                       "(aligned, region transferred, mass estimated; docs/import.md)")
    i.add_argument("path", metavar="MESH_OR_CLOUD",
                   help=".obj/.stl/.ply/.off mesh or .pcd/.ply/.npy point cloud, metres")
    i.add_argument("--category", required=True, help="drill, spray_bottle or mug")
    i.add_argument("--mass", type=_float_in(0.0, open_low=True), default=None, metavar="KG",
                   help="the object's mass (default: the category's density times the mesh's volume)")
    i.add_argument("--region", nargs=4, metavar=("NAME", "X", "Y", "Z"), default=None,
                   help="a point of the functional part (trigger or handle) in the file's frame, metres "
                        "(default: transferred from the category's canonical instance by the fit)")
    i.add_argument("--transform", default=None, metavar='"RX RY RZ X Y Z"',
                   help="the alignment, stated: roll pitch yaw (deg) and x y z (m), canonical <- file "
                        "(default: automatic)")
    i.add_argument("--grasp", default=None, metavar="FILE",
                   help="the grasp file whose fit is reported (default: models/grasps/<category>_handwritten.yaml)")
    i.add_argument("--name", default=None, help="instance name (default: from the file name)")
    i.add_argument("--model", default=None, help="category model file (default: models/trained/<category>.npz)")
    i.add_argument("--out", default=None, metavar="DIR",
                   help="output directory (default: out/objects/<category>/<name>)")
    i.set_defaults(func=_cmd_import_object)

    f = sub.add_parser("film", help="film one grasp trial: a PNG strip of the station at the phases of the motion "
                       "(the hand-written grasp on an object, or a benchmark record's trial again)")
    f.add_argument("--category", default=None, help="drill, spray_bottle or mug (hand-written grasp)")
    f.add_argument("--instance", default=None, help="embedded instance (default: the category's first)")
    f.add_argument("--object", default=None, metavar="DIR", help="an imported object's directory")
    f.add_argument("--seed", type=_int_at_least(0, MAX_SEED), default=None,
                   help="seed of a random placement (default: the scenario's pose)")
    f.add_argument("--shift", type=float, nargs=3, metavar=("DX", "DY", "DZ"), default=None,
                   help="move the hand-written grasp by this much (m, object frame)")
    f.add_argument("--grasp", default=None, metavar="FILE",
                   help="a grasp file to film instead of the category's (models/grasps/<category>_handwritten.yaml)")
    f.add_argument("--record", default=None, metavar="FILE", help="a benchmark records file: film its --index trial")
    f.add_argument("--index", type=_int_at_least(0), default=0, help="the record's position in --record (from 0)")
    f.add_argument("--data", default="out/benchmark/data", help="where the benchmark's objects are generated")
    f.add_argument("--closeup", action="store_true",
                   help="cameras that follow the trigger or handle from 22 cm (front, side, below) instead of the "
                        "station-scale views: where the fingers meet it")
    f.add_argument("--size", type=_int_at_least(16, 2000), nargs=2, metavar=("W", "H"), default=None,
                   help="pixels of one frame (default 180 x 180, close-up 300 x 300)")
    f.add_argument("--out", default=None, help="PNG (default: out/film/<instance>_...png)")
    f.set_defaults(func=_cmd_film)

    g = sub.add_parser("search-grasp", help="search the category's hand-written grasp for robustness (cross-entropy "
                       "over pose and finger variations, scored by perturbed simulated trials)")
    g.add_argument("--category", required=True, help="drill, spray_bottle or mug")
    g.add_argument("--instances", nargs="+", default=None,
                   help="committed instances to search on (default: every other one; the rest stay for checking; "
                        "none when --objects is given)")
    g.add_argument("--objects", nargs="+", default=None, metavar="DIR",
                   help="imported objects of the category to search on too (catgrasp import-object; e.g. a stress "
                        "copy out/benchmark/data/stress/spray_bottle/spray_bottle_01_large)")
    g.add_argument("--grasp", default=None,
                   help="the grasp file to start from (default: models/grasps/<category>_handwritten.yaml)")
    g.add_argument("--rounds", type=_int_at_least(1, 50), default=3)
    g.add_argument("--population", type=_int_at_least(2, 200), default=10)
    g.add_argument("--elite", type=_int_at_least(1, 200), default=3)
    g.add_argument("--perturbations", type=_int_at_least(1, 50), default=1,
                   help="trials per instance and candidate (the first at the nominal placement)")
    g.add_argument("--mass-scale", type=float, nargs=2, metavar=("LOW", "HIGH"), default=(0.7, 1.3),
                   help="the perturbed trials' object mass, times the instance's (uniform; e.g. 1 3 for bottles "
                        "that may be full)")
    g.add_argument("--height-error", type=float, default=0.0, metavar="M", help=HEIGHT_ERROR_HELP)
    g.add_argument("--freeze", nargs="+", default=None, help="variation parameters kept at 0 (e.g. dx dy dz)")
    g.add_argument("--screen", nargs="+", default=None, metavar="OBJECT",
                   help="committed instances or imported objects' directories on which every candidate is first "
                        "checked by the planner, without simulation: a candidate refused on more than "
                        "--screen-max-refused of them is drawn again, so each round simulates a full population the "
                        "planner accepts (up to 40 x population draws a round; e.g. every tuning object)")
    g.add_argument("--screen-max-refused", type=_int_at_least(0, 10_000), default=0)
    g.add_argument("--seed", type=_int_at_least(0, MAX_SEED), default=0)
    g.add_argument("--cache", default="out/grasp_search/cache", help="trial cache (resumes an interrupted search)")
    g.add_argument("--workers", type=_int_at_least(0, MAX_WORKERS), default=None)
    g.add_argument("--ray", default=None, help="run trials on a Ray cluster: 'auto', 'local' or the head's address")
    g.add_argument("--out", default=None, help="directory of the record and the new grasp file "
                   "(default: out/grasp_search/<category>)")
    g.set_defaults(func=_cmd_search_grasp)

    v = sub.add_parser("view", help="inspect a trained model's latent shape space in Meshcat (sliders)")
    v.add_argument("category")
    v.add_argument("--model", help="model file (default: models/trained/<category>.npz)")
    v.add_argument("--html", help="also write a static HTML page with every training instance")
    v.add_argument("--once", action="store_true", help="draw, write --html, print the URL and exit")
    v.set_defaults(func=_cmd_view)
    return p


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except CatgraspError as e:  # our own one-line messages, whole: their end says what to do
        print(f"catgrasp: error: {one_line(e, with_type=False, limit=None)}", file=sys.stderr)
        return 2
    except (OSError, ImportError) as e:  # a file system problem, a missing optional library: no traceback
        print(f"catgrasp: error: {type(e).__name__}: {one_line(e, with_type=False)}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("catgrasp: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
