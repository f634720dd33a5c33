"""Speed levers with their fidelity guard: the same reference trials at the default and at faster settings.

    python benchmarks/bench_fidelity.py [--lever time_step=0.02 ...] [--workers 2] [--json out/fidelity.json]

The reference set (>= 60 trials, successes and failures, three categories):
the hand-written grasp on every committed instance (13 drills, 17 spray
bottles, 15 mugs) and the same grasp moved 1 cm forward on the first five of
each category (which fail more often). Every trial is run at the default
plant settings (``--baseline``, default: the station's ``PlantSpec`` as it
was tuned, time step 5 ms) and at each lever (``--lever``: ``PlantSpec``
fields replaced, e.g. ``time_step=0.02``, ``hand_resolution_hint=0.010``,
``time_step=0.01,discrete_contact_approximation=lagged``; and the trial's option
``stop_when_decided=true|false``: end a trial where its failure is decided, the
default of ``run_grasp_trial``, which the baseline turns off). Printed per setting: wall
time of the whole set on the workers, the median real-time rate of a trial
(simulated / wall seconds of one core), and the agreement with the default
(grasp and functional outcome both equal) -- issue 17's guard is >= 95 % -- and
how many failure reasons are the same as the baseline's.
Trials run as tasks of ``catgrasp_drake.runner.run_tasks`` (no cache: each
run measures).
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "diagrams"))

CATEGORIES = ("drill", "spray_bottle", "mug")
SHIFTED_PER_CATEGORY = 5
SHIFT_O = (0.0, 0.01, 0.0)
#: The physics the station was tuned with, every trial simulated to its end (issue 17's "today's outcome").
BASELINE = "time_step=0.005,stop_when_decided=false"


#: Settings that are options of the trial, not ``PlantSpec`` fields.
TRIAL_OPTIONS = ("stop_when_decided",)


def parse_setting(text: str) -> dict:
    """``"time_step=0.02,hand_resolution_hint=0.01"`` -> ``{"time_step": 0.02, ...}`` (PlantSpec fields, and
    ``stop_when_decided=true|false``: the trial's option)."""
    from dataclasses import fields

    from catgrasp_drake.station.scenario import PlantSpec

    known = {f.name: f.type for f in fields(PlantSpec)}
    out = {}
    for item in filter(None, (t.strip() for t in text.split(","))):
        key, sep, value = item.partition("=")
        if key in TRIAL_OPTIONS and value in ("true", "false"):
            out[key] = value == "true"
            continue
        if not sep or key not in known:
            raise SystemExit(f"--lever/--baseline: {item!r} is not <PlantSpec field>=<value> or "
                             f"stop_when_decided=true|false (fields: {', '.join(sorted(known))})")
        try:
            out[key] = float(value)
        except ValueError:
            out[key] = value
    return out


def fidelity_task(spec: dict) -> dict:
    """One reference trial at one setting -> outcome and timing (module level: runs in workers)."""
    from catgrasp_drake.station.handwritten import load_handwritten_motion, shifted_motion
    from catgrasp_drake.station.scenario import load_scenario, with_instance
    from catgrasp_drake.trial import run_grasp_trial

    category, instance = spec["category"], spec["instance"]
    base = with_instance(load_scenario(f"{category}_default"), instance)
    options = {k: v for k, v in spec["plant"].items() if k in TRIAL_OPTIONS}
    plant = {k: v for k, v in spec["plant"].items() if k not in TRIAL_OPTIONS}
    scenario = base.replace(plant=replace(base.plant, **plant))
    motion = load_handwritten_motion(category, instance)
    if spec["shifted"]:
        motion = shifted_motion(motion, category, instance, SHIFT_O)
    t0 = time.perf_counter()
    r = run_grasp_trial(scenario, motion, **options)
    return {"grasp": r.grasp_success, "functional": r.functional_success, "reason": r.failure_reason,
            "sim_s": r.sim_time_s, "wall_s": time.perf_counter() - t0}


def reference_set() -> list[dict]:
    from catgrasp_drake.data.dataset import list_instances

    out = []
    for category in CATEGORIES:
        names = list_instances(category)
        out += [{"category": category, "instance": n, "shifted": False} for n in names]
        out += [{"category": category, "instance": n, "shifted": True} for n in names[:SHIFTED_PER_CATEGORY]]
    return out


def main(argv=None) -> int:
    from catgrasp_drake.runner import run_tasks

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", default=BASELINE,
                    help=f"the settings whose outcomes the levers must reproduce (default {BASELINE!r})")
    ap.add_argument("--lever", nargs="+", default=["time_step=0.01", "time_step=0.02"],
                    help="settings to try, each '<PlantSpec field>=<value>[,...]'")
    ap.add_argument("--accurate", default=None,
                    help="also run this (e.g. 'time_step=0.001') and print every setting's agreement with it: "
                         "how far the baseline itself is from a converged answer")
    ap.add_argument("--reuse", default=None, metavar="JSON",
                    help="take the settings already measured in this --json file of an earlier run")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--json", default=None, help="also write every trial's outcome here")
    args = ap.parse_args(argv)

    trials = reference_set()
    settings = [args.baseline] + list(args.lever) + ([args.accurate] if args.accurate else [])
    plants = {s: parse_setting(s) for s in settings}
    results = {}
    if args.reuse:
        earlier = json.loads(Path(args.reuse).read_text())
        if earlier["trials"] != trials:
            raise SystemExit(f"--reuse {args.reuse}: made on another reference set")
        results = {s: (r, float("nan")) for s, r in earlier["results"].items() if s in settings}
        results = {s: (r, earlier.get("wall_s", {}).get(s, float("nan"))) for s, (r, _) in results.items()}
    for setting in settings:
        if setting in results:
            print(f"setting {setting}: reused from {args.reuse}", file=sys.stderr, flush=True)
            continue
        specs = [t | {"plant": plants[setting]} for t in trials]
        t0 = time.perf_counter()
        outcomes = run_tasks(fidelity_task, specs, cache_dir=None, code_version="fidelity", workers=args.workers)
        results[setting] = ([o.result for o in outcomes], time.perf_counter() - t0)
        print(f"setting {setting}: {len(specs)} trials in {results[setting][1]:.0f} s", file=sys.stderr, flush=True)

    base, _ = results[args.baseline]
    print(f"reference set: {len(trials)} trials (hand-written grasp on every committed instance, and moved "
          f"{SHIFT_O[1] * 100:.0f} cm on {SHIFTED_PER_CATEGORY} per category); {args.workers} workers")
    def agreement(xs, ys) -> str:
        n = sum(1 for a, b in zip(xs, ys) if "grasp" in a and "grasp" in b
                and (a["grasp"], a["functional"]) == (b["grasp"], b["functional"]))
        return f"{n}/{len(xs)} ({100 * n / len(xs):.0f} %)"

    def same_reason(xs, ys) -> str:
        n = sum(1 for a, b in zip(xs, ys) if a.get("reason") == b.get("reason"))
        return f"{n}/{len(xs)}"

    extra = f" agreement with {args.accurate} |" if args.accurate else ""
    print(f"| setting | wall time of the set | simulated s of the set | median real-time rate | grasped | functional "
          f"| agreement | same failure reason |{extra}")
    print("|---|---:|---:|---:|---:|---:|---:|---:|" + ("---:|" if args.accurate else ""))
    for setting in settings:
        rs, wall = results[setting]
        ok = [r for r in rs if "grasp" in r]
        rates = [r["sim_s"] / r["wall_s"] for r in ok if r["sim_s"] > 0]
        name = f"{setting} (baseline)" if setting == args.baseline else setting
        tail = f" {agreement(results[args.accurate][0], rs)} |" if args.accurate else ""
        sim = sum(r["sim_s"] for r in ok)
        print(f"| {name} | {wall:.0f} s | {sim:.0f} s | {statistics.median(rates):.2f}x "
              f"| {sum(r['grasp'] for r in ok)}/{len(rs)} | {sum(r['functional'] for r in ok)}/{len(rs)} "
              f"| {agreement(base, rs)} | {same_reason(base, rs)} |{tail}")
    if args.json:
        from catgrasp_drake.core.fileio import atomic_write_text

        record = {"trials": trials, "results": {s: r for s, (r, _) in results.items()},
                  "wall_s": {s: w for s, (_, w) in results.items()}}
        atomic_write_text(args.json, json.dumps(record, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    from catgrasp_drake.errors import run_script

    raise SystemExit(run_script(main))
