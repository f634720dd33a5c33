"""Trial-by-trial agreement of two benchmark records files (same split, methods, placements).

    python compare.py BEFORE.jsonl AFTER.jsonl
"""

import json
import sys

MEASURED = ("scale", "pose_error_mm", "yaw_error_deg", "rise_m", "tilt_deg")


def load(path):
    out = {}
    for line in open(path):
        r = json.loads(line)
        if "method" in r:  # (the header line has none)
            out[(r["category"], r["instance"], r["method"], r["view"], r["trial"])] = r
    return out


def main():
    a, b = load(sys.argv[1]), load(sys.argv[2])
    keys = sorted(set(a) & set(b))
    same = 0
    for k in keys:
        ra, rb = a[k], b[k]
        eq = all(ra[f] == rb[f] for f in ("grasp", "functional", "reason"))
        same += eq
        moved = {f: (ra[f], rb[f]) for f in MEASURED if ra.get(f) != rb.get(f)}
        print(k[0], k[1], "same" if eq else "CHANGED", ra["functional"], rb["functional"], ra["reason"], rb["reason"],
              moved or "")
    print(f"{same}/{len(keys)} outcomes (grasp, functional, reason) agree; only in one file: {len(set(a) ^ set(b))}")
    for name, d in (("first", a), ("second", b)):
        print(name, "functional", sum(r["functional"] for r in d.values()), "of", len(d))


if __name__ == "__main__":
    main()
