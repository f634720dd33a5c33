"""Session 45: the probe's views per category under the rule of README.md (reads the committed JSONL files).

"today": the visibility-aware energies' ranking (``latent``); "plain": the probe's own plain energies (sigma2
profiled, the raw cloud); "latent_plain": that method's ranking (the fit's plain energies, at most 300 points at the
best fit's sigma2; the JSON field ``first_product``).

    python benchmarks/results/experiments/s45_yaw_rank/tables.py
"""

from __future__ import annotations

import json
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROUND_DEG, RIGHT_DEG = 45.0, 15.0


def _err(view: dict, key: str) -> float:
    """|yaw error| (deg) of the hypothesis the ranking ``key`` (first_today, first_plain, first_product) puts first."""
    return abs(view["hypotheses"][view[key]]["yaw_error_deg"])


def _changed_line(view: dict, where: str = "") -> str:
    """One view whose first-ranked hypothesis latent_plain changes: yaw errors, and by how much each energy prefers
    the hypothesis it ranks first (nats; today's = visibility-aware, latent_plain's = plain at <= 300 points)."""
    h, a, b = view["hypotheses"], view["first_today"], view["first_product"]
    vis_gap = h[b]["energy"] - h[a]["energy"]
    plain = view["product_plain_energy"]
    return (f"  {where or view['category']} {view['instance']} placement {view['trial']}: "
            f"yaw error {h[a]['yaw_error_deg']:+.1f} -> {h[b]['yaw_error_deg']:+.1f} deg; "
            f"today's pick ahead by {vis_gap:.0f} nats (visibility-aware), "
            f"latent_plain's by {plain[a] - plain[b]:.0f} (plain); scale {h[a]['scale']:.3f} / {h[b]['scale']:.3f}, "
            f"{view['n_observed']} observed points")


def sim_check() -> None:
    """The rule's second step: val drill_00's 12 placements simulated before and after the change (records)."""
    def load(name):
        lines = (HERE / name).read_text().splitlines()[1:]
        return {r["trial"]: r for r in map(json.loads, lines)}

    before, after = load("sim_val_drill00_before.jsonl"), load("sim_val_drill00_after.jsonl")
    kept = ("code_version", "timings", "posterior")  # fields allowed to differ on a view whose choice is unchanged
    print("| placement | executed hypothesis: before | after | before | after | other fields equal |")
    print("|---:|---:|---:|---|---|---|")
    for k in sorted(before):
        a, b = before[k], after[k]
        same = all(a[f] == b.get(f) for f in a if f not in kept)
        outcome = ["functional" if r["functional"] else r["reason"] for r in (a, b)]
        print(f"| {k} | {a['posterior']['hypothesis']} | {b['posterior']['hypothesis']} | {outcome[0]} | {outcome[1]} "
              f"| {'yes' if same else 'no'} |")
    print(f"\nfunctional: before {sum(r['functional'] for r in before.values())}/{len(before)}, "
          f"after {sum(r['functional'] for r in after.values())}/{len(after)}")


def heldout() -> None:
    """Held-out drill views (measurement, after the rule): where latent_plain's ranking changes the first grasp."""
    print("| held-out views | views | turned round: today | latent_plain | paper's fit "
          "| changed by latent_plain (instance placement) |")
    print("|---|---:|---:|---:|---:|---|")
    changed_views = []
    for f in sorted(HERE.glob("heldout_*.jsonl")):
        views = [json.loads(line) for line in f.read_text().splitlines()]
        changed_views += [(f.stem.removeprefix("heldout_"), r) for r in views if r["first_today"] != r["first_product"]]
        changed = [f"{r['instance']} {r['trial']}" for r in views if r["first_today"] != r["first_product"]]
        paper = sum(r["paper_yaw_error_deg"] is not None and abs(r["paper_yaw_error_deg"]) > ROUND_DEG for r in views)
        turned = [sum(_err(r, k) > ROUND_DEG for r in views) for k in ("first_today", "first_product")]
        print(f"| {f.stem.removeprefix('heldout_')} | {len(views)} | {turned[0]} | {turned[1]} | {paper} "
              f"| {', '.join(changed) or '—'} |")
    print("\nHeld-out views whose first-ranked hypothesis latent_plain changes:")
    for where, r in changed_views:
        print(_changed_line(r, where))


def main() -> None:
    rows = [json.loads(line) for f in sorted(HERE.glob("val_*.jsonl")) for line in f.read_text().splitlines()]
    print("| category | views | turned round: today | plain | latent_plain | paper's fit | within 15°: today | plain "
          "| latent_plain | paper's fit | any hypothesis within 15° | first hypothesis changed: plain "
          "| latent_plain | rule |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    for cat in sorted({r["category"] for r in rows}):
        views = [r for r in rows if r["category"] == cat]
        keys = ("first_today", "first_plain", "first_product")
        turned = {k: sum(_err(r, k) > ROUND_DEG for r in views) for k in keys}
        right = {k: sum(_err(r, k) <= RIGHT_DEG for r in views) for k in keys}
        paper = [abs(r["paper_yaw_error_deg"]) for r in views if r["paper_yaw_error_deg"] is not None]
        oracle = sum(any(abs(h["yaw_error_deg"]) <= RIGHT_DEG for h in r["hypotheses"]) for r in views)
        changed = [r for r in views if r["first_today"] != r["first_plain"]]
        product_changed = sum(r["first_today"] != r["first_product"] for r in views)
        passes = turned["first_plain"] < turned["first_today"] and right["first_plain"] >= right["first_today"]
        print(f"| {cat} | {len(views)} | {turned['first_today']} | {turned['first_plain']} | {turned['first_product']} "
              f"| {sum(e > ROUND_DEG for e in paper)} | {right['first_today']} | {right['first_plain']} "
              f"| {right['first_product']} "
              f"| {sum(e <= RIGHT_DEG for e in paper)} | {oracle} | {len(changed)} | {product_changed} "
              f"| {'passes' if passes else 'fails'} |")
    print()
    print("Validation views whose first-ranked hypothesis latent_plain changes:")
    for r in rows:
        if r["first_today"] != r["first_product"]:
            print(_changed_line(r))
    # the margin core.inference.PLAIN_ENERGY_POINTS quotes: drill views with a right and a turned-round hypothesis
    gaps = []
    for r in rows:
        pairs = list(zip(r["hypotheses"], r["product_plain_energy"]))
        right = [e for h, e in pairs if abs(h["yaw_error_deg"]) <= RIGHT_DEG]
        turned = [e for h, e in pairs if abs(h["yaw_error_deg"]) > ROUND_DEG]
        if r["category"] == "drill" and right and turned:
            gaps.append(min(turned) - min(right))
    gaps.sort()
    print(f"\nValidation drill views with a right and a turned-round hypothesis: {len(gaps)}; the turned one's plain "
          f"energy above the right one's by at least {gaps[0]:.0f} nats, median {gaps[len(gaps) // 2]:.0f}")


if __name__ == "__main__":
    main()
    print()
    sim_check()
    print()
    heldout()
