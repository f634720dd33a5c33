"""Session 34: the fresh split (seed 20261205) at six placements, latent against its baselines (measured only).

    python benchmarks/results/experiments/s34_fresh_six/compare.py FRESH6.jsonl [COMMITTED.jsonl]

Prints, per category, functional successes of latent, nearest and rigid + scale over the six placements and
over the new ones (3-5) alone, latent minus each baseline with its paired 95 % interval (bootstrap over
instances, ``benchmark.stats.paired_bootstrap``), and how many of placements 0-2 repeat the committed
records' verdict (``COMMITTED``, default ``benchmarks/results/fresh_seed20261205.jsonl``).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[4]))

from catgrasp_drake.benchmark.stats import paired_bootstrap  # noqa: E402


def load(path):
    with open(path) as f:
        return [r for r in (json.loads(line) for line in f) if "trial" in r]


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    recs = load(argv[0])
    committed = load(argv[1] if len(argv) > 1 else "benchmarks/results/fresh_seed20261205.jsonl")
    key = lambda r: (r["category"], r["method"], r["instance"], r["trial"], r.get("view", "single"),  # noqa: E731
                     r.get("data_seed"))
    old = {key(r): r for r in committed}
    by = {key(r): r for r in recs}
    for category in ("drill", "spray_bottle", "mug"):
        print(f"\n{category}")
        n = 1 + max(k[3] for k in by)
        for trials, label in ((range(n), f"placements 0-{n - 1}"), (range(3, n), f"placements 3-{n - 1} (new)")):
            keys = sorted({(k[2], k[3]) for k in by if k[0] == category and k[3] in trials})
            if not keys:
                continue
            seed = next(k[5] for k in by if k[0] == category)
            f = {m: [bool(by[(category, m, i, t, "single", seed)]["functional"]) for i, t in keys]
                 for m in ("latent", "nearest", "rigid")}
            inst = [i for i, _ in keys]
            line = ", ".join(f"{m} {sum(v)}/{len(v)}" for m, v in f.items())
            diffs = []
            for m in ("nearest", "rigid"):
                p = paired_bootstrap(inst, f["latent"], f[m])
                diffs.append(f"latent - {m} {100 * p.diff:+.1f} pp [{100 * p.low:+.1f}, {100 * p.high:+.1f}]")
            print(f"  {label}: {line}; " + "; ".join(diffs))
        same = total = 0
        for k, r in by.items():
            if k[0] == category and k[3] < 3 and k in old:
                total += 1
                same += (r["grasp"], r["functional"], r["reason"]) == (old[k]["grasp"], old[k]["functional"],
                                                                       old[k]["reason"])
        if total:
            print(f"  placements 0-2: {same}/{total} verdicts as committed")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
