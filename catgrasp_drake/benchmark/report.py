"""The benchmark's records files and the Markdown tables built from them.

Records are JSON lines (one trial per line, keys sorted) after a header line
``{"format": "catgrasp.benchmark_records", "format_version": 1, "records": <count>,
"sha256": <hex of the record lines>}``, written atomically by
:func:`write_benchmark_records` and checked by :func:`load_benchmark_records`.

The tables are a deterministic function of the records (intervals from
:mod:`catgrasp_drake.benchmark.stats` with the seed and draw count below; no
dates, no machine names), so the README and ``docs/benchmark.md`` can be
rebuilt from the committed records and compared by a test
(:func:`check_markdown`). They live in Markdown files between marker lines::

    <!-- benchmark:summary -->
    ...generated, replaced by update_markdown...
    <!-- /benchmark:summary -->

Markers: ``summary`` (:func:`summary_table`: per split and category, the latent
method's single-view grasp and functional rates and the best baseline; for the
README) and ``full`` (:func:`benchmark_tables`: every table, for
``docs/benchmark.md``).
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Iterable, Mapping, Sequence

import numpy as np

from catgrasp_drake.benchmark.stats import PAIR_KEY, bootstrap_rate, pair_records, paired_bootstrap
from catgrasp_drake.errors import InputError, one_line

RECORDS_FORMAT = "catgrasp.benchmark_records"
FORMAT_VERSION = 1
#: Bootstrap settings of every interval in the tables.
N_BOOT = 2000
SEED = 0
LEVEL = 0.95
DEFAULT_PHYSICS = "default"
#: Display orders (values not listed follow, sorted by name).
SPLITS = ("test", "fresh", "ycb", "ais", "val", "stress")
SPLIT_TITLES = {"test": "held-out generated instances",
                "fresh": "generated instances of newly drawn data-set seeds (each named <instance>@<data_seed>): "
                         "never seen",
                "ycb": "real scans (YCB)",
                "ais": "real drills (AIS clouds; trigger pinned, session 21: the session-7 model's transfer)",
                "val": "generated instances of the validation seed: novel draws (a TUNING set, not a measure)",
                "stress": "the committed instances stretched to real proportions (a TUNING set, not a measure)",
                "smoke": "smoke run"}
#: Splits of tuned-on objects: in the full tables, never in the README's summary of held-out results.
TUNING_SPLITS = ("val", "stress")
CATEGORIES = ("drill", "spray_bottle", "mug")
VIEWS = ("single", "active", "two", "three", "full")
METHODS = ("latent", "latent_map", "latent_fast", "latent_plain", "paper", "nearest", "rigid", "cpd", "true_object")
METHOD_LABELS = {"true_object": "true-object planner (ablation)", "latent_map": "latent, MAP fit only (ablation)",
                 "latent_fast": "latent, fast fit (ablation)",
                 "latent_plain": "latent, hypotheses weighted by the plain energy (ablation)"}
#: Methods that are not baselines (privileged information, or the method itself with a part switched
#: off): never the "best baseline" of the summary.
ABLATIONS = ("true_object", "latent_map", "latent_fast", "latent_plain")
#: Categories pooled in the overall tables (stratified bootstrap by category).
POOLED = ("drill", "spray_bottle")
MARKERS = ("summary", "full")
#: Fields every record must have.
REQUIRED_FIELDS = ("split", "category", "instance", "trial", "view", "method", "physics", "grasp", "functional")
#: Fields that identify one trial of one method; ``seed`` (the benchmark's seed) and ``data_seed`` (the fresh
#: split's data-set seed) are optional in a record. Two records with the same values are the same trial twice
#: (e.g. a records file passed twice): refused.
TRIAL_KEY = PAIR_KEY + ("method", "seed", "data_seed")
#: Pairing keys: methods on the same trials; physics settings on the same trials (same method).
METHOD_PAIR_KEY = PAIR_KEY + ("seed",)
PHYSICS_PAIR_KEY = ("split", "category", "instance", "trial", "view", "method", "seed")

_OPEN = re.compile(r"<!--\s*benchmark:([A-Za-z0-9_.-]+)\s*-->")
_CLOSE = re.compile(r"<!--\s*/benchmark:([A-Za-z0-9_.-]+)\s*-->")


# ----------------------------------------------------------------------------- records files
def _missing_fields(r) -> list[str]:
    if not isinstance(r, dict):
        return list(REQUIRED_FIELDS)
    return [k for k in REQUIRED_FIELDS if k not in r]


def _trial_key(record: dict) -> str:
    """One trial of one method (:data:`TRIAL_KEY`) as a comparable string."""
    return json.dumps([record.get(f) for f in TRIAL_KEY], default=str)


def _validated(records: Iterable[dict], *, unique: bool = False) -> list[dict]:
    records = list(records)
    for i, r in enumerate(records):
        if not isinstance(r, dict):
            raise InputError(f"benchmark record {i}: expected a dict, got {type(r).__name__}")
        missing = _missing_fields(r)
        if missing:
            raise InputError(f"benchmark record {i}: missing fields {', '.join(missing)}")
    if unique:
        seen = set()
        for r in records:
            k = _trial_key(r)
            if k in seen:
                trial = ", ".join(f"{f} {r.get(f)}" for f in TRIAL_KEY)
                raise InputError(f"the records hold the same trial twice ({trial}); is a records file passed twice?")
            seen.add(k)
    return records


def _object_name(record: dict) -> str:
    """The object a record's trial was run on: its instance, and for the fresh split its data-set seed too
    (``drill_00@20261205``): two seeds' instances share names but are different objects."""
    if record["split"] == "fresh" and record.get("data_seed") is not None:
        return f"{record['instance']}@{record['data_seed']}"
    return record["instance"]


def _tabled(records: Iterable[dict]) -> list[dict]:
    """The records as the tables use them: ``instance`` names the object (:func:`_object_name`), so that
    pairing keys and the bootstrap's resampled units never merge two seeds' objects, and a ``seed`` field
    (None where absent) for the pairing keys."""
    return [r | {"instance": _object_name(r), "seed": r.get("seed")} for r in records]


def write_benchmark_records(path: str | Path, records: Iterable[dict]) -> None:
    """Write trial records as JSON lines (keys sorted), atomically, after a header with their count and sha256."""
    from catgrasp_drake.core.fileio import write_json_lines

    write_json_lines(path, _validated(records), RECORDS_FORMAT, FORMAT_VERSION)


def merged_records(existing: Iterable[dict], new: Iterable[dict]) -> list[dict]:
    """``existing`` with every trial that ``new`` holds replaced by ``new``'s record (same :data:`TRIAL_KEY`),
    in place, and ``new``'s other trials appended: how one category or method is re-run into a records file
    that holds others (``catgrasp benchmark --merge``)."""
    rerun = {_trial_key(r): r for r in _validated(new, unique=True)}
    kept = {_trial_key(r): r for r in _validated(existing, unique=True)}  # dicts keep the file's order
    return _validated([rerun.get(k, r) for k, r in kept.items()] + [r for k, r in rerun.items() if k not in kept])


def _record_files(paths) -> list[Path]:
    if isinstance(paths, (str, Path)):
        paths = [paths]
    out = []
    for p in paths:
        p = Path(p)
        out.extend(sorted(p.glob("*.jsonl")) if p.is_dir() else [p])
    return out


def _load_one(path: Path) -> list[dict]:
    from catgrasp_drake.core.fileio import read_json_lines

    def check(r):
        missing = _missing_fields(r)
        return f"lacks the fields {', '.join(missing)}" if missing else None

    return read_json_lines(path, RECORDS_FORMAT, FORMAT_VERSION, what="benchmark records",
                           rerun="re-run the benchmark", check=check)


def load_benchmark_records(paths: str | Path | Iterable[str | Path]) -> list[dict]:
    """Read one or more records files (a folder stands for its ``*.jsonl``), concatenated in the order given.

    Raises ModelFileError, with a one-line message naming the file, when one is
    unreadable, has no header, is of another format or version, does not
    match its header's record count and checksum, or holds a line that is not
    a trial record.
    """
    out: list[dict] = []
    for path in _record_files(paths):
        out.extend(_load_one(path))
    return out


# ----------------------------------------------------------------------------- formatting helpers
def _ordered(values: Iterable, preferred: Sequence) -> list:
    present = set(values)
    return [v for v in preferred if v in present] + sorted(v for v in present if v not in preferred)


def _label(method: str) -> str:
    return METHOD_LABELS.get(method, method)


def _category(c: str) -> str:
    return c.replace("_", " ")


def _split_title(split: str) -> str:
    title = SPLIT_TITLES.get(split)
    return f"Split `{split}`: {title}" if title else f"Split `{split}`"


def _pct(x: float) -> str:
    return f"{100.0 * x + 0.0:.0f}"  # + 0.0: no "-0"


def _single_instance(instances, strata=None) -> bool:
    """Whether some stratum (or the whole set) holds fewer than 2 instances: no interval can be given."""
    inst = np.asarray(list(instances), dtype=object)
    groups = np.asarray(list(strata), dtype=object) if strata is not None else np.zeros(len(inst), dtype=object)
    return any(len(set(inst[groups == g])) < 2 for g in set(groups))


def _rate(instances, successes, strata=None) -> str:
    """``k/n (p %) [lo–hi %]`` with the instance bootstrap interval; an em dash for no trials.

    With fewer than 2 instances (in some stratum) an instance bootstrap has nothing to resample:
    the interval is replaced by "[1 instance]" rather than a degenerate [p–p %].
    """
    s = np.asarray(successes, dtype=bool)
    if len(s) == 0:
        return "—"
    if _single_instance(instances, strata):
        return f"{int(s.sum())}/{len(s)} ({_pct(s.mean())} %) [1 instance]"
    p, lo, hi = bootstrap_rate(instances, s, strata=strata, n_boot=N_BOOT, seed=SEED, level=LEVEL)
    return f"{int(s.sum())}/{len(s)} ({_pct(p)} %) [{_pct(lo)}–{_pct(hi)} %]"


def _pp(x: float) -> str:
    v = 100.0 * x + 0.0
    return "0" if f"{v:.0f}" in ("0", "-0") else f"{v:+.0f}"


def _seconds(x: float, digits: int = 1) -> str:
    return "—" if not np.isfinite(x) else f"{x:.{digits}f} s"


def _timing(r: dict, name: str) -> float:
    t = r.get("timings")
    v = t.get(name) if isinstance(t, dict) else None
    try:
        v = float(v)
    except (TypeError, ValueError):
        return float("nan")
    return v


def _median(values) -> float:
    v = np.asarray([x for x in values if np.isfinite(x)], dtype=float)
    return float(np.median(v)) if len(v) else float("nan")


def _total(values) -> float:
    v = [x for x in values if np.isfinite(x)]
    return float(np.sum(v)) if v else float("nan")


def _table(header: Sequence[str], align: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |",
             "|" + "|".join("---:" if a == "r" else "---" for a in align) + "|"]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return "\n".join(lines)


def _field(records: Sequence[dict], name: str) -> list:
    return [r[name] for r in records]


def _outcome(records: Sequence[dict], name: str) -> np.ndarray:
    return np.array([bool(r[name]) for r in records], dtype=bool)


def _select(records: Sequence[dict], **eq) -> list[dict]:
    return [r for r in records if all(r[k] == v for k, v in eq.items())]


# ----------------------------------------------------------------------------- tables
_RATE_HEADER = ("method", "trials", "grasp", "functional", "instances", "median time / trial")
_RATE_ALIGN = ("l", "r", "l", "l", "r", "r")


def _method_rows(records: Sequence[dict], *, stratified: bool) -> list[list[str]]:
    rows = []
    for method in _ordered(_field(records, "method"), METHODS):
        rs = _select(records, method=method)
        inst = _field(rs, "instance")
        strata = _field(rs, "category") if stratified else None
        n_inst = len({(r["category"], r["instance"]) for r in rs})
        rows.append([_label(method), str(len(rs)), _rate(inst, _outcome(rs, "grasp"), strata),
                     _rate(inst, _outcome(rs, "functional"), strata), str(n_inst),
                     _seconds(_median(_timing(r, "total") for r in rs))])
    return rows


def _difference_rows(records: Sequence[dict]) -> list[list[str]]:
    """Latent minus each other method: paired functional-rate differences per category and pooled."""
    rows = []
    latent_all = _select(records, method="latent")
    if not latent_all:
        return rows
    categories = _ordered(_field(records, "category"), CATEGORIES)
    for view in _ordered(_field(records, "view"), VIEWS):
        cells = [(_category(c), [c]) for c in categories]
        if all(c in categories for c in POOLED):
            cells.append((" + ".join(_category(c) for c in POOLED), list(POOLED)))
        for name, cats in cells:
            latent = [r for r in latent_all if r["view"] == view and r["category"] in cats]
            for method in _ordered(_field(records, "method"), METHODS):
                if method == "latent":
                    continue
                other = [r for r in records if r["method"] == method and r["view"] == view and r["category"] in cats]
                if not latent or not other:
                    continue
                pairs = pair_records(latent, other, key=METHOD_PAIR_KEY)
                if not len(pairs) or (len(cats) > 1 and set(pairs.field("category")) != set(cats)):
                    continue  # (a pooled row needs pairs in every pooled category)
                a, b = pairs.outcomes("functional")
                strata = pairs.field("category") if len(cats) > 1 else None
                d = paired_bootstrap(pairs.field("instance"), a, b, strata=strata,
                                     n_boot=N_BOOT, seed=SEED, level=LEVEL)
                if _single_instance(pairs.field("instance"), strata):
                    interval, excludes, frac = f"{_pp(d.diff)} pp [1 instance]", "—", "—"
                else:
                    interval = f"{_pp(d.diff)} pp [{_pp(d.low)}, {_pp(d.high)}]"
                    excludes, frac = ("yes" if d.excludes_zero else "no"), f"{d.frac_le_zero:.3f}"
                rows.append([name, f"{view}", _label(method), str(len(pairs)),
                             f"{int(a.sum())}/{len(a)} ({_pct(d.rate_a)} %)",
                             f"{int(b.sum())}/{len(b)} ({_pct(d.rate_b)} %)", interval, excludes, frac])
    return rows


def _split_section(split: str, records: Sequence[dict], committed: Mapping[str, str] | None = None) -> list[str]:
    title = _split_title(split)
    seeds = sorted({r["data_seed"] for r in records if r.get("data_seed") is not None})
    if seeds:
        title += f" (data-set seed{'s' if len(seeds) > 1 else ''} {', '.join(map(str, seeds))})"
    out = [f"### {title}", ""]
    categories = _ordered(_field(records, "category"), CATEGORIES)
    views = _ordered(_field(records, "view"), VIEWS)
    for category in categories:
        for view in views:
            rs = _select(records, category=category, view=view)
            if rs:
                other = _other_model(rs, committed)
                note = (f" († {other} of these {len(rs)} trials were run with another {_category(category)} model "
                        "than the committed one)") if other else ""
                out += [f"**{_category(category)}, {view} view**{note}", "",
                        _table(_RATE_HEADER, _RATE_ALIGN, _method_rows(rs, stratified=False)), ""]
    if all(c in categories for c in POOLED):
        for view in views:
            rs = [r for r in records if r["view"] == view and r["category"] in POOLED]
            if rs:
                out += [f"**{' + '.join(_category(c) for c in POOLED)}, {view} view** "
                        f"(bootstrap stratified by category)", "",
                        _table(_RATE_HEADER, _RATE_ALIGN, _method_rows(rs, stratified=True)), ""]
    rows = _difference_rows(records)
    if rows:
        out += ["**Latent minus baseline, functional success** (paired trials; difference in percentage "
                "points with its 95 % interval; P(≤ 0): fraction of bootstrap draws with difference ≤ 0)", "",
                _table(("category", "view", "baseline", "paired trials", "latent functional", "baseline functional",
                        "difference [95 %]", "interval excludes 0", "P(≤ 0)"),
                       ("l", "l", "l", "r", "l", "l", "l", "l", "r"), rows), ""]
    return out


def _physics_section(records: Sequence[dict]) -> list[str]:
    default = [r for r in records if r["physics"] == DEFAULT_PHYSICS]
    others = [r for r in records if r["physics"] != DEFAULT_PHYSICS]
    if not others:
        return []
    rows, unpaired = [], 0
    for split in _ordered(_field(others, "split"), SPLITS):
        for physics in sorted({r["physics"] for r in others if r["split"] == split}):
            setting = _select(others, split=split, physics=physics)
            for method in _ordered(_field(setting, "method"), METHODS):
                mine = _select(setting, method=method)
                pairs = pair_records(_select(default, split=split, method=method), mine, key=PHYSICS_PAIR_KEY)
                unpaired += pairs.unpaired_b
                if not len(pairs):
                    continue
                inst, strata = pairs.field("instance"), pairs.field("category")
                ga, gb = pairs.outcomes("grasp")
                fa, fb = pairs.outcomes("functional")
                agree = (ga == gb) & (fa == fb)
                rows.append([f"`{split}`", f"`{physics}`", _label(method), str(len(pairs)),
                             _rate(inst, ga, strata), _rate(inst, gb, strata),
                             _rate(inst, fa, strata), _rate(inst, fb, strata), _rate(inst, agree, strata)])
    out = ["### Physics sensitivity", "",
           "Each setting on its own trials, next to the same trials (instance, placement, view, method) under "
           "the default physics; agreement: both the grasp and the functional outcome equal the default's.", ""]
    if rows:
        out += [_table(("split", "physics", "method", "paired trials", "grasp (default)", "grasp (setting)",
                        "functional (default)", "functional (setting)", "agreement"),
                       ("l", "l", "l", "r", "l", "l", "l", "l", "l"), rows), ""]
    if unpaired:
        out += [f"{unpaired} trials of other physics settings have no default-physics counterpart and are "
                f"left out.", ""]
    return out


def _reason_label(r: dict) -> str:
    reason = r.get("reason")
    if reason is None or reason == "":
        return "(success)" if r["functional"] else "(unspecified)"
    return f"`{reason}`"


def _failure_section(records: Sequence[dict]) -> list[str]:
    latent = _select(records, method="latent")
    if not latent:
        return []
    out = ["### Failure reasons (latent method, default physics, both views)", ""]
    for split in _ordered(_field(latent, "split"), SPLITS):
        rs = _select(latent, split=split)
        categories = _ordered(_field(rs, "category"), CATEGORIES)
        counts: dict[str, dict[str, int]] = {}
        for r in rs:
            row = counts.setdefault(_reason_label(r), {})
            row[r["category"]] = row.get(r["category"], 0) + 1
        order = sorted(counts, key=lambda k: (-sum(counts[k].values()), k))
        rows = [[k] + [str(counts[k].get(c, 0)) for c in categories] + [str(sum(counts[k].values()))]
                for k in order]
        rows.append(["all trials"] + [str(len(_select(rs, category=c))) for c in categories] + [str(len(rs))])
        out += [f"**`{split}`**", "",
                _table(["reason"] + [_category(c) for c in categories] + ["total"],
                       ["l"] + ["r"] * (len(categories) + 1), rows), ""]
    return out


def _posterior_section(records: Sequence[dict]) -> list[str]:
    """How often the shape posterior changed the latent method's grasp, and what it did (paired with latent_map)."""
    latent = [r for r in _select(records, method="latent") if r.get("posterior")]
    if not latent:
        return []
    maps = {tuple(r[k] for k in METHOD_PAIR_KEY): r for r in _select(records, method="latent_map")}
    rows = []
    for split in _ordered(_field(latent, "split"), SPLITS):
        for category in _ordered(_field(_select(latent, split=split), "category"), CATEGORIES):
            for view in _ordered(_field(_select(latent, split=split, category=category), "view"), VIEWS):
                rs = _select(latent, split=split, category=category, view=view)
                post = [r["posterior"] for r in rs]
                changed = [r for r in rs if r["posterior"].get("search_rank", 0) or r["posterior"]["hypothesis"]]
                paired = [(r, maps.get(tuple(r[k] for k in METHOD_PAIR_KEY))) for r in changed]
                paired = [(a, b) for a, b in paired if b is not None]
                won = sum(a["functional"] and not b["functional"] for a, b in paired)
                lost = sum(b["functional"] and not a["functional"] for a, b in paired)
                rows.append([f"`{split}`", _category(category), view, str(len(rs)),
                             f"{np.mean([p['hypotheses'] for p in post]):.2f}",
                             str(sum(bool(p.get("search_rank", 0)) for p in post)),
                             str(sum(p["hypothesis"] != 0 for p in post)), str(sum(p["candidate"] > 0 for p in post)),
                             str(len(changed)), f"+{won} / −{lost}" if paired else "—"])
    return ["### Shape posterior (latent method)", "",
            "Distinct shape hypotheses per trial (mean); trials where the MAP fit came from another start than "
            "the yaw search's best (refined to a lower energy), where the executed grasp is another hypothesis' "
            "(more posterior support, or the MAP's grasp could not be planned), where the planner fell back to a "
            "later candidate; changed = either of the first two; on the changed trials, functional successes "
            "gained / lost against the same trial with the MAP fit only (`latent_map`).", "",
            _table(("split", "category", "view", "trials", "hypotheses", "MAP ≠ search's best",
                    "grasp of another hypothesis", "planner fell back", "changed", "functional vs MAP only"),
                   ("l", "l", "l", "r", "r", "r", "r", "r", "r", "l"), rows), ""]


#: Pairing key of a view against the single view: the same trial (object, placement, camera, noise) and method.
VIEW_PAIR_KEY = ("split", "category", "instance", "trial", "method", "seed")


def _more_views_section(records: Sequence[dict]) -> list[str]:
    """Each view with further cameras against the single view on the same trials: functional rates, how many
    trials fitted 1, 2 and 3 views, and the paired difference."""
    rows = []
    for view in [v for v in _ordered(_field(records, "view"), VIEWS) if v in ("active", "two", "three")]:
        mine = _select(records, view=view)
        for split in _ordered(_field(mine, "split"), SPLITS):
            for category in _ordered(_field(_select(mine, split=split), "category"), CATEGORIES):
                for method in _ordered(_field(_select(mine, split=split, category=category), "method"), METHODS):
                    a_all = _select(records, split=split, category=category, method=method, view="single")
                    b_all = _select(mine, split=split, category=category, method=method)
                    pairs = pair_records(a_all, b_all, key=VIEW_PAIR_KEY)
                    if not len(pairs):
                        continue
                    a, b = pairs.outcomes("functional")
                    d = paired_bootstrap(pairs.field("instance"), b, a, n_boot=N_BOOT, seed=SEED, level=LEVEL)
                    interval = (f"{_pp(d.diff)} pp [1 instance]" if _single_instance(pairs.field("instance"), None)
                                else f"{_pp(d.diff)} pp [{_pp(d.low)}, {_pp(d.high)}]")
                    used = [int(r.get("views_used", 1)) for r in pairs.b]
                    rows.append([f"`{split}`", _category(category), _label(method), view, str(len(pairs)),
                                 " / ".join(str(used.count(n)) for n in (1, 2, 3)), f"{int(a.sum())}/{len(a)}",
                                 f"{int(b.sum())}/{len(b)}", interval])
    if not rows:
        return []
    return ["### More views", "",
            "The same trials seen once (`single`) and with further cameras, the first turned +90° and then −90° "
            "about the object (`active`: the next view merged in only while the views so far leave the yaw open, "
            "at most three; before session 25 at most two; `two`, `three`: always); views 1 / 2 / 3 = trials "
            "whose estimate fitted that many; difference = that view's minus the single view's functional rate, "
            "paired trials, 95 % interval.", "",
            _table(("split", "category", "method", "view", "paired trials", "views 1 / 2 / 3", "single functional",
                    "functional", "difference [95 %]"), ("l", "l", "l", "l", "r", "r", "l", "l", "l"), rows), ""]


def _cost_section(records: Sequence[dict]) -> list[str]:
    def row(name, method, rs):
        wall = _total(_timing(r, "total") for r in rs)
        sim = _total(_timing(r, "simulated_s") for r in rs)
        return [name, method, str(len(rs)),
                "—" if not np.isfinite(wall) else f"{wall:.0f} s ({wall / 3600:.2f} h)",
                "—" if not np.isfinite(sim) else f"{sim:.0f} s",
                _seconds(_median(_timing(r, "perceive") for r in rs), 2),
                _seconds(_median(_timing(r, "estimate") for r in rs), 2),
                _seconds(_median(_timing(r, "plan") for r in rs), 2)]

    rows = []
    for split in _ordered(_field(records, "split"), SPLITS):
        rs = _select(records, split=split)
        for method in _ordered(_field(rs, "method"), METHODS):
            rows.append(row(f"`{split}`", _label(method), _select(rs, method=method)))
    rows.append(row("all", "all", list(records)))
    return ["### Cost (every trial, every physics setting)", "",
            "Wall time: the sum of the trials' `timings.total`, i.e. seconds of one core; simulated: the sum of "
            "the simulated seconds.", "",
            _table(("split", "method", "trials", "wall time", "simulated", "median perceive", "median estimate",
                    "median plan"), ("l", "l", "r", "r", "r", "r", "r", "r"), rows), ""]


def benchmark_tables(records: Iterable[dict], *, committed: Mapping[str, str] | None = None) -> str:
    """Every benchmark table as Markdown (the ``full`` marker; module docstring). Deterministic.

    ``committed``: ``{category: model sha256}`` (:func:`committed_models`); a split's category table any of whose
    trials carry another ``model_sha256`` says how many. InputError if a record lacks a field of
    :data:`REQUIRED_FIELDS` or two records are the same trial.
    """
    records = _tabled(_validated(records, unique=True))
    if not records:
        return "No benchmark records."
    default = [r for r in records if r["physics"] == DEFAULT_PHYSICS]
    out = [f"Rates: successes/trials (pooled rate) [{100 * LEVEL:.0f} % interval: percentile bootstrap over "
           f"instances, all trials of a drawn instance together; {N_BOOT} draws, seed {SEED}]. "
           f"Default physics unless stated.", ""]
    for split in _ordered(_field(default, "split"), SPLITS):
        out += _split_section(split, _select(default, split=split), committed)
    out += _physics_section(records)
    out += _posterior_section(default)
    out += _more_views_section(default)
    out += _failure_section(default)
    out += _cost_section(records)
    return "\n".join(out).rstrip("\n") + "\n"


def committed_models() -> dict[str, str]:
    """``{category: sha256}`` of the committed trained models (``models/trained/<category>.npz``) that exist."""
    from catgrasp_drake.core.fileio import file_sha256
    from catgrasp_drake.demo import default_model_path

    return {c: file_sha256(default_model_path(c)) for c in CATEGORIES if default_model_path(c).is_file()}


def _other_model(records: Sequence[dict], models: Mapping[str, str] | None) -> int:
    """How many of ``records`` were run with another model of their category than ``models`` names (0 if
    ``models`` is None; categories ``models`` does not name, e.g. an example folder's, are not judged)."""
    if not models:
        return 0
    return sum(1 for r in records if r["category"] in models and r.get("model_sha256") != models[r["category"]])


OTHER_MODEL_NOTE = ("† some of the row's trials were run with another model of the category than the committed "
                      "`models/trained/<category>.npz` (their `model_sha256` differs, e.g. an earlier one): re-run "
                      "them before quoting the row.")


def summary_table(records: Iterable[dict], *, tuning: bool = False,
                  committed: Mapping[str, str] | None = None) -> str:
    """The README's compact table (the ``summary`` marker): per split and category, single view, default physics,
    the latent method's grasp and functional rates and the baseline with the highest functional rate; held-out
    splits only (not :data:`TUNING_SPLITS`) unless ``tuning`` (the CLI's summary of a tuning run).

    ``committed``: ``{category: model sha256}`` (:func:`committed_models`); a row any of whose shown trials (latent's,
    the baseline's) carry another ``model_sha256`` is marked † (:data:`OTHER_MODEL_NOTE`)."""
    records = [r for r in _tabled(_validated(records, unique=True))
               if r["physics"] == DEFAULT_PHYSICS and r["view"] == "single"
               and (tuning or r["split"] not in TUNING_SPLITS)]
    rows, marked = [], False
    for split in _ordered(_field(records, "split"), SPLITS):
        for category in _ordered(_field(_select(records, split=split), "category"), CATEGORIES):
            rs = _select(records, split=split, category=category)
            latent = _select(rs, method="latent")
            if not latent:
                continue
            best, best_rate = None, -1.0
            for method in _ordered(_field(rs, "method"), METHODS):
                if method == "latent" or method in ABLATIONS:
                    continue
                f = _outcome(_select(rs, method=method), "functional")
                if f.mean() > best_rate:  # ties: the earlier method in METHODS
                    best, best_rate = method, float(f.mean())
            b = _select(rs, method=best) if best is not None else []
            if best is None:
                base = ["—", "—"]
            else:
                trials = "" if len(b) == len(latent) else f" ({len(b)} trials)"  # e.g. run on one fresh seed only
                base = [_label(best) + trials, _rate(_field(b, "instance"), _outcome(b, "functional"))]
            inst = _field(latent, "instance")
            other = _other_model(latent + b, committed) > 0  # the trials the row shows
            marked |= other
            rows.append([f"`{split}`", _category(category) + (" †" if other else ""), str(len(latent)),
                         _rate(inst, _outcome(latent, "grasp")), _rate(inst, _outcome(latent, "functional"))] + base)
    if not rows:
        return "No single-view benchmark trials."
    table = _table(("split", "category", "trials", "latent grasp", "latent functional", "best baseline",
                    "baseline functional"), ("l", "l", "r", "l", "l", "l", "l"), rows)
    note = "\n\n" + OTHER_MODEL_NOTE if marked else ""
    return (table + "\n\n" + f"Single view, default physics; [{100 * LEVEL:.0f} % interval], percentile bootstrap "
            f"over instances ({N_BOOT} draws, seed {SEED}). Every table: `docs/benchmark.md`.{note}\n")


def markdown_tables(records: Iterable[dict], committed: Mapping[str, str] | None = None) -> dict[str, str]:
    """``{marker: Markdown}`` for every marker of :data:`MARKERS`; ``committed``: as :func:`benchmark_tables`."""
    records = _validated(records)
    return {"summary": summary_table(records, committed=committed),
            "full": benchmark_tables(records, committed=committed)}


# ----------------------------------------------------------------------------- Markdown files
def _regions(text: str, path, names: Iterable[str] | None = None) -> dict[str, tuple[int, int]]:
    """``{name: (start, end)}`` of the text between each marker pair; InputError if missing or unbalanced."""
    opens: dict[str, list[re.Match]] = {}
    closes: dict[str, list[re.Match]] = {}
    for m in _OPEN.finditer(text):
        opens.setdefault(m.group(1), []).append(m)
    for m in _CLOSE.finditer(text):
        closes.setdefault(m.group(1), []).append(m)
    wanted = sorted(set(opens) | set(closes)) if names is None else list(names)
    out = {}
    for name in wanted:
        o, c = opens.get(name, []), closes.get(name, [])
        if not o and not c:
            raise InputError(f"{path}: no <!-- benchmark:{name} --> marker")
        if len(o) != 1 or len(c) != 1 or c[0].start() < o[0].end():
            raise InputError(f"{path}: unbalanced benchmark:{name} markers ({len(o)} opening, {len(c)} closing; "
                             f"expected one <!-- benchmark:{name} --> before one <!-- /benchmark:{name} -->)")
        out[name] = (o[0].end(), c[0].start())
    spans = sorted(out.values())
    for (_, e0), (s1, _) in zip(spans, spans[1:]):
        if s1 < e0:
            raise InputError(f"{path}: benchmark markers are nested or overlap")
    for name, (s, e) in out.items():
        if _OPEN.search(text, s, e) or _CLOSE.search(text, s, e):
            raise InputError(f"{path}: benchmark:{name} region contains another benchmark marker")
    return out


def _read_markdown(path: Path) -> str:
    try:
        return path.read_bytes().decode("utf-8")
    except (OSError, ValueError) as e:
        raise InputError(f"{path}: unreadable Markdown file ({one_line(e)})") from None


def _replaced(text: str, path, tables_by_marker: Mapping[str, str]) -> str:
    regions = _regions(text, path, tables_by_marker)
    for name, (start, end) in sorted(regions.items(), key=lambda kv: -kv[1][0]):
        text = text[:start] + "\n" + tables_by_marker[name].strip("\n") + "\n" + text[end:]
    return text


def update_markdown(path: str | Path, tables_by_marker: Mapping[str, str]) -> str:
    """Replace the text between ``<!-- benchmark:<name> -->`` and ``<!-- /benchmark:<name> -->`` for each name.

    Writes atomically (only if something changed) and returns the new text.
    One-line InputError if a marker is missing or unbalanced; the file is then left untouched.
    """
    from catgrasp_drake.core.fileio import atomic_write_text

    path = Path(path)
    text = _read_markdown(path)
    new = _replaced(text, path, tables_by_marker)
    if new != text:
        atomic_write_text(path, new)
    return new


def _markers_in(text: str, path) -> list[str]:
    names = [n for n in _regions(text, path) if n in MARKERS]
    if not names:
        raise InputError(f"{path}: no benchmark markers (expected <!-- benchmark:NAME --> ... "
                         f"<!-- /benchmark:NAME --> with NAME in {', '.join(MARKERS)})")
    return names


def check_markdown(path: str | Path, records: Iterable[dict], committed: Mapping[str, str] | None = None) -> list[str]:
    """The markers of ``path`` (among :data:`MARKERS`) whose content differs from what ``records`` give (and
    ``committed``, as :func:`markdown_tables`)."""
    path = Path(path)
    text = _read_markdown(path)
    names = _markers_in(text, path)
    regions = _regions(text, path, names)
    tables = markdown_tables(records, committed)
    return [n for n in names if text[regions[n][0]:regions[n][1]].strip("\n") != tables[n].strip("\n")]


def report(records_paths: str | Path | Iterable[str | Path], markdown_paths: str | Path | Iterable[str | Path],
           *, write: bool = True, committed: Mapping[str, str] | None = None) -> dict[str, str]:
    """Build the tables from the records files and fill every marker found in each Markdown file.

    Returns ``{markdown path: its new text}``; writes the files (atomically) unless ``write`` is False.
    ``committed``: as :func:`markdown_tables`. A Markdown file without any marker of :data:`MARKERS` is an
    InputError.
    """
    from catgrasp_drake.core.fileio import atomic_write_text

    tables = markdown_tables(load_benchmark_records(records_paths), committed)
    if isinstance(markdown_paths, (str, Path)):
        markdown_paths = [markdown_paths]
    new_texts = {}
    for p in markdown_paths:  # check every file before writing any
        p = Path(p)
        text = _read_markdown(p)
        new_texts[str(p)] = (text, _replaced(text, p, {n: tables[n] for n in _markers_in(text, p)}))
    if write:
        for p, (old, new) in new_texts.items():
            if new != old:
                atomic_write_text(p, new)
    return {p: new for p, (_, new) in new_texts.items()}
