"""The paper's evaluation protocol (section IV, DESIGN.md section 7): Table I with baselines.

Leave-two-out cross-validation: the canonical instance always trains; the
other instances are taken in pairs, each pair tested on a model trained on
all the rest (drill 13 -> 6 models / 12 test instances, spray bottle 17 -> 7 /
14, mug 15 -> 7 / 14). Every test instance is grasped from a fully observed
cloud (four cameras around it) and from a single depth view, at a seeded
random placement, by every method of :mod:`catgrasp_drake.baselines` -- the
same placement, view and seed for each method.

A trial is one task of :func:`catgrasp_drake.runner.run_tasks` (parallel
workers, on-disk cache keyed by spec and code version, so an interrupted run
resumes without redoing finished trials): observe -> predict -> execute
(:func:`catgrasp_drake.trial.run_grasp_trial`, the predicted world
motion expressed in the true object frame) -> judge. Fold models are trained
with :func:`catgrasp_drake.training.train_category` and kept under the output
folder (re-used when present), their grasp trials cached in ``<out_dir>/training_trials``.

Outputs (``evaluate``): per-trial records (JSON lines), Table I per method next
to the paper's figures (also as a PNG chart), inference times, and the confidence analysis (AUROC of
the estimator's confidence against functional success; success rate when the
least confident 20 % are refused). Every file is written atomically; ``records.jsonl``
starts with a header line (format, version, record count, sha256 of the record lines) and
``report.json`` carries its format, version and sha256, checked by :func:`load_records` and
:func:`load_report`. A trial's cache key includes the sha256 of its fold model file, so a
retrained model never reuses trials of the old one.
"""

from __future__ import annotations

import json
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from catgrasp_drake.baselines import METHODS, predict_grasp
from catgrasp_drake.category_model import CategoryModel
from catgrasp_drake.core.fileio import atomic_write_text, file_sha256, read_json_lines, text_sha256, write_json_lines
from catgrasp_drake.data.dataset import list_instances
from catgrasp_drake.errors import InputError, ModelFileError, one_line
from catgrasp_drake.runner import code_fingerprint, run_tasks
from catgrasp_drake.station.scenario import load_scenario, random_placement, with_instance
from catgrasp_drake.training import TrainingConfig, train_category
from catgrasp_drake.transfer import VIEWS, observe
from catgrasp_drake.trial import TRIAL_CODE_PATHS, run_grasp_trial
from catgrasp_drake.viz.charts import table_chart

#: The views evaluated by default, in the paper's Table I order (full view first).
DEFAULT_VIEWS = ("full", "single")
RECORDS_FORMAT = "catgrasp.eval_records"
REPORT_FORMAT = "catgrasp.eval_report"
FORMAT_VERSION = 1
#: Fields of a trial record that are wall-clock timings (vary from run to run); every other field
#: is a deterministic function of the trial's spec and the code.
TIMING_FIELDS = ("inference_s", "observe_s", "trial_wall_s")
#: Number of leave-two-out folds per category (DESIGN.md section 7).
FOLDS = {"drill": 6, "spray_bottle": 7, "mug": 7}
#: The paper's Table I (successes, trials) per category: grasp / functional x full / partial view.
PAPER_TABLE = {
    "drill": {"grasp": {"full": (7, 12), "single": (6, 12)}, "functional": {"full": (4, 12), "single": (3, 12)}},
    "spray_bottle": {"grasp": {"full": (8, 14), "single": (9, 14)},
                     "functional": {"full": (3, 14), "single": (6, 14)}},
}


@dataclass(frozen=True)
class EvalConfig:
    """What to evaluate (SI units). ``instances``: restrict the test instances (e.g. a quick run)."""

    category: str
    methods: tuple[str, ...] = METHODS
    views: tuple[str, ...] = DEFAULT_VIEWS
    seed: int = 0
    folds: int | None = None  # None: FOLDS[category]
    instances: tuple[str, ...] | None = None
    samples_per_instance: int = 12  # training budget of each fold model
    workers: int | None = None
    out_dir: str = "out/eval"
    ray: str | None = None  # Ray address ("auto", "local", "host:port") or None: local worker processes

    def __post_init__(self):
        bad = [m for m in self.methods if m not in METHODS]
        if bad:
            raise InputError(f"unknown methods {bad}; known: {', '.join(METHODS)}")
        bad = [v for v in self.views if v not in VIEWS]
        if bad:
            raise InputError(f"unknown views {bad}; known: {', '.join(VIEWS)}")


def leave_two_out(category: str, folds: int | None = None) -> list[tuple[list[str], list[str]]]:
    """``[(train instances, test instances), ...]``: the canonical (first) instance always trains."""
    names = list_instances(category)
    n = FOLDS.get(category, (len(names) - 1) // 2) if folds is None else int(folds)
    if not 1 <= n <= (len(names) - 1) // 2:
        raise InputError(f"folds: expected 1..{(len(names) - 1) // 2} for {len(names)} {category} instances, got {n}")
    others = names[1:1 + 2 * n]
    out = []
    for k in range(n):
        test = others[2 * k: 2 * k + 2]
        out.append(([m for m in names if m not in test], test))
    return out


def eval_trial_task(spec: dict) -> dict:
    """Worker task: one test instance, view, method and seed on one fold model -> a JSON-able record."""
    model = CategoryModel.load(spec["_model"], category=spec["category"])
    scenario = random_placement(with_instance(load_scenario(f"{spec['category']}_default"), spec["instance"]),
                                spec["seed"])
    t0 = time.perf_counter()
    observed_W, camera_W = observe(scenario, spec["view"])
    t_observe = time.perf_counter() - t0
    pred = predict_grasp(spec["method"], model, observed_W, scenario.table.pose.matrix(), camera_W=camera_W)
    record = {k: spec[k] for k in ("category", "fold", "instance", "view", "method", "seed")}
    record |= {"num_points": int(len(observed_W)), "confidence": float(pred.estimate.confidence),
               "inference_s": float(pred.timing["total"]), "observe_s": t_observe, "detail_method": pred.detail}
    if not pred.ok:
        return record | {"grasp": False, "functional": False, "reason": "no_estimate", "detail": pred.detail}
    result = run_grasp_trial(scenario, pred.motion_W.in_object(scenario.X_WO()))
    return record | {"grasp": result.grasp_success, "functional": result.functional_success,
                     "reason": result.failure_reason, "detail": result.detail, "plan_status": result.plan_status,
                     "sim_s": result.sim_time_s, "trial_wall_s": result.wall_time_s}


def eval_code_version() -> str:
    root = Path(__file__).resolve().parent
    return code_fingerprint(list(TRIAL_CODE_PATHS) + [root / "baselines.py", root / "core", root / "transfer.py",
                                                       root / "category_model.py", root / "evaluation.py"])


def fold_model(config: EvalConfig, fold: int, train: list[str], progress=None) -> Path:
    """The fold's model file under ``out_dir`` (trained unless already there)."""
    path = Path(config.out_dir) / config.category / f"fold{fold}.npz"
    if path.is_file():
        try:
            CategoryModel.load(path, category=config.category)  # checks format, version and checksum
        except (ModelFileError, InputError) as e:
            raise ModelFileError(
                f"{one_line(e, with_type=False)} (fold {fold} model; delete it to retrain it)") from None
        return path
    # the fold models' grasp trials are cached under out_dir too (shared by the folds and categories), so
    # an interrupted evaluation resumes from the same folder whatever the working directory
    tc = TrainingConfig(samples_per_instance=config.samples_per_instance, seed=config.seed,
                        workers=config.workers, canonical_instance=train[0], ray=config.ray,
                        cache_dir=str(Path(config.out_dir) / "training_trials"))
    train_category(config.category, train, tc, progress=progress).save(path)
    return path


def trial_specs(config: EvalConfig, models: dict[int, str], folds) -> list[dict]:
    """One task spec per (test instance, view, method); ``model_sha256`` keys the cache by the model's content
    (``_model``, its path, is not part of the key: :func:`~catgrasp_drake.runner.task_key`)."""
    digests = {k: file_sha256(m) for k, m in models.items()}
    specs = []
    for k, (_, test) in enumerate(folds):
        for instance in test:
            if config.instances is not None and instance not in config.instances:
                continue
            for view in config.views:
                for method in config.methods:
                    specs.append({"task": "eval_trial", "category": config.category, "fold": k,
                                  "_model": models[k], "model_sha256": digests[k], "instance": instance,
                                  "view": view, "method": method, "seed": config.seed})
    return specs


# ----------------------------------------------------------------------------- tables
def table_one(records: list[dict]) -> dict:
    """``{method: {"grasp"|"functional": {view: [successes, trials]}}, ...}`` from trial records."""
    out: dict = {}
    for r in records:
        cell = out.setdefault(r["method"], {"grasp": {}, "functional": {}})
        for kind in ("grasp", "functional"):
            s, n = cell[kind].get(r["view"], [0, 0])
            cell[kind][r["view"]] = [s + bool(r[kind]), n + 1]
    return out


def auroc(scores, labels) -> float | None:
    """Area under the ROC curve of ``scores`` for binary ``labels`` (Mann-Whitney U; ties count half)."""
    s = np.asarray(scores, float)
    y = np.asarray(labels, bool)
    pos, neg = s[y], s[~y]
    if len(pos) == 0 or len(neg) == 0:
        return None
    greater = (pos[:, None] > neg[None, :]).sum() + 0.5 * (pos[:, None] == neg[None, :]).sum()
    return float(greater / (len(pos) * len(neg)))


def confidence_analysis(records: list[dict], refuse_fraction: float = 0.2) -> dict:
    """AUROC of confidence vs functional success, and the success rate after refusing the least confident."""
    rs = [r for r in records if np.isfinite(r.get("confidence", np.nan))]
    if not rs:
        return {"trials": 0}
    conf = np.array([r["confidence"] for r in rs])
    ok = np.array([bool(r["functional"]) for r in rs])
    threshold = float(np.quantile(conf, refuse_fraction))
    kept = conf > threshold if refuse_fraction > 0 else np.ones(len(rs), bool)
    return {"trials": len(rs), "auroc": auroc(conf, ok), "success_all": float(ok.mean()),
            "threshold": threshold, "kept": int(kept.sum()),
            "success_kept": float(ok[kept].mean()) if kept.any() else None}


def format_table(category: str, table: dict) -> str:
    """Markdown Table I: methods x (grasp, functional) x (full, single), with the paper's row."""
    lines = [f"| {category} | grasp, full | grasp, single view | functional, full | functional, single view |",
             "|---|---|---|---|---|"]

    def cell(c, kind, view):
        s, n = c.get(kind, {}).get(view, (0, 0))
        return f"{s}/{n} ({100 * s / n:.0f} %)" if n else "—"

    if category in PAPER_TABLE:
        lines.append("| paper (RA-L 2018) | " + " | ".join(
            cell(PAPER_TABLE[category], k, v) for k in ("grasp", "functional") for v in ("full", "single")) + " |")
    for method, c in table.items():
        lines.append(f"| {method} | " + " | ".join(cell(c, k, v) for k in ("grasp", "functional")
                                                 for v in ("full", "single")) + " |")
    return "\n".join(lines)


@dataclass
class EvalReport:
    config: EvalConfig
    records: list[dict]
    table: dict
    confidence: dict
    inference_s: dict = field(default_factory=dict)  # method -> {"median", "max"}
    wall_s: float = 0.0


def evaluate(config: EvalConfig, *, progress: Callable[[str, int, int], None] | None = None) -> EvalReport:
    """Run the protocol (module docstring); writes ``<out_dir>/<category>/records.jsonl`` and ``report.json``."""
    t0 = time.perf_counter()
    folds = leave_two_out(config.category, config.folds)
    wanted = set(config.instances) if config.instances is not None else None
    models = {}
    for k, (train, test) in enumerate(folds):
        if wanted is not None and not wanted & set(test):
            continue
        models[k] = str(fold_model(config, k, train, progress=progress))
    specs = trial_specs(config, models, folds)
    if not specs:
        raise InputError(f"no evaluation trials: instances {config.instances} are not test instances of any fold")
    out = Path(config.out_dir) / config.category
    outcomes = run_tasks(eval_trial_task, specs, cache_dir=out / "trial_cache", code_version=eval_code_version(),
                         workers=config.workers, ray_address=config.ray,
                         progress=(lambda o, d, t: progress("trials", d, t)) if progress else None)
    records = []
    for spec, o in zip(specs, outcomes):
        r = o.result
        if r.get("status") == "error":
            r = {k: spec[k] for k in ("category", "fold", "instance", "view", "method", "seed")} | {
                "grasp": False, "functional": False, "reason": "error", "detail": str(r.get("error", ""))[:300],
                "confidence": float("nan"), "inference_s": float("nan")}
        records.append(r)
    times = {}
    for m in config.methods:
        ts = [r["inference_s"] for r in records if r["method"] == m and np.isfinite(r.get("inference_s", np.nan))]
        if ts:
            times[m] = {"median": float(np.median(ts)), "max": float(np.max(ts))}
    report = EvalReport(config, records, table_one(records),
                        confidence_analysis([r for r in records if r["method"] == "latent"]), times,
                        time.perf_counter() - t0)
    write_records(out / "records.jsonl", records)
    write_chart(config.category, report.table, out / "table.png")
    write_report(out / "report.json", {
        "config": asdict(config), "table": report.table, "confidence_latent": report.confidence,
        "inference_s": times, "wall_s": report.wall_s, "paper": PAPER_TABLE.get(config.category)})
    return report


def write_chart(category: str, table: dict, path) -> None:
    """PNG bar chart of Table I, the paper's figures first (where the paper has them)."""
    rows = ({"paper": PAPER_TABLE[category]} if category in PAPER_TABLE else {}) | table
    table_chart(category, rows, path)


def write_records(path: str | Path, records: list[dict]) -> None:
    """Write trial records as JSON lines (atomically), after a header line with their count and sha256."""
    write_json_lines(path, records, RECORDS_FORMAT, FORMAT_VERSION)


def load_records(path: str | Path) -> list[dict]:
    """Read a ``records.jsonl`` back (one JSON object per trial, after the header line).

    Raises ModelFileError, with a one-line message naming the file, when it is
    unreadable, not JSON lines, of another format or version, or does not
    match its header's record count and checksum. (A file without the header
    line, written before it existed, is read without the checks.)
    """
    return read_json_lines(path, RECORDS_FORMAT, FORMAT_VERSION, what="evaluation records",
                           rerun="re-run the evaluation", headerless_ok=True)


def write_report(path: str | Path, report: dict) -> None:
    """Write ``report.json`` atomically with its format, version and sha256 (over the other fields)."""
    body = json.loads(json.dumps(report, default=str))  # what the file will hold
    out = {"format": REPORT_FORMAT, "format_version": FORMAT_VERSION} | body
    out["sha256"] = text_sha256(json.dumps(out, sort_keys=True))
    atomic_write_text(path, json.dumps(out, indent=1, sort_keys=True) + "\n")


def load_report(path: str | Path) -> dict:
    """Read ``report.json`` back; ModelFileError (one line, naming the file) when corrupt or of another format."""
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as e:
        raise ModelFileError(f"{path}: unreadable evaluation report ({one_line(e)})") from None
    if not isinstance(data, dict) or data.get("format") != REPORT_FORMAT:
        raise ModelFileError(f"{path}: not an evaluation report (format {REPORT_FORMAT!r})")
    if data.get("format_version") != FORMAT_VERSION:
        raise ModelFileError(f"{path}: format version {data.get('format_version')} but this catgrasp_drake reads "
                             f"version {FORMAT_VERSION}; re-run the evaluation")
    body = {k: v for k, v in data.items() if k != "sha256"}
    if data.get("sha256") != text_sha256(json.dumps(body, sort_keys=True)):
        raise ModelFileError(f"{path}: checksum mismatch; the file is corrupt or was edited")
    return body
