"""Session 38: copies of the validation split's spray bottles under names of their own (``spray_bottle_val_NN``).

    python benchmarks/results/experiments/s38_spray_val_grasp/copy_val.py [--data out/benchmark/data] [--out DIR]

The validation split (``catgrasp benchmark --split val``, seed 902870906) names its instances as the committed
data set does (``spray_bottle_00`` ...), so ``catgrasp search-grasp --objects`` refuses them beside committed
instances. This writes each bottle's mesh, SDF and annotations again with the instance renamed; nothing else
changes (the mesh bytes are the same).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[4]
sys.path.insert(0, str(ROOT))


def main(argv=None) -> int:
    from catgrasp_drake.benchmark.runner import VAL_SEED, ensure_test_split
    from catgrasp_drake.core.fileio import atomic_write_text

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(ROOT / "out" / "benchmark" / "data"))
    ap.add_argument("--out", default=str(ROOT / "out" / "s38" / "val_objects"))
    args = ap.parse_args(argv)
    root = ensure_test_split(args.data, VAL_SEED) / "spray_bottle"
    for src in sorted(p for p in root.iterdir() if p.is_dir()):
        old = src.name
        new = old.replace("spray_bottle_", "spray_bottle_val_")
        dst = Path(args.out) / new
        dst.mkdir(parents=True, exist_ok=True)
        (dst / f"{new}.obj").write_bytes((src / f"{old}.obj").read_bytes())
        atomic_write_text(dst / f"{new}.sdf", (src / f"{old}.sdf").read_text().replace(old, new))
        ann = json.loads((src / "annotations.json").read_text())
        ann["instance"] = new
        atomic_write_text(dst / "annotations.json", json.dumps(ann, indent=2) + "\n")
        print(dst)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
