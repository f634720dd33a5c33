"""Session 37: the lowest tipping angles of every generated split's objects and of the real imports (no simulation).

    python benchmarks/results/experiments/s37_val_drills/tipping.py [--data out/benchmark/data]

For the committed instances and the test, validation and three fresh seeds' instances (generated on demand, as the
benchmark does) and the AIS and YCB objects the benchmark imports: per split and category, the instances' lowest
tipping angles (``catgrasp_drake.data.meshes.tipping_angle_deg``, at each object's annotated centre of mass).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import trimesh

sys.path.insert(0, str(Path(__file__).resolve().parents[4]))

from catgrasp_drake.benchmark.runner import BenchmarkConfig, split_objects  # noqa: E402
from catgrasp_drake.data.dataset import CATEGORIES, list_instances, objects_dir, read_annotations  # noqa: E402
from catgrasp_drake.data.meshes import tipping_angle_deg  # noqa: E402

FRESH_SEEDS = (20261205, 20261206, 1729527019)


def angle(directory: Path, name: str) -> float:
    mesh = trimesh.load(directory / f"{name}.obj", force="mesh")
    return tipping_angle_deg(mesh, read_annotations(directory / "annotations.json")["center_of_mass"])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default="out/benchmark/data")
    args = ap.parse_args(argv)
    groups = {("committed", c): [(objects_dir() / c / n, n) for n in list_instances(c)] for c in CATEGORIES}
    configs = [("test", {}), ("val", {})] + [(f"fresh {s}", {"data_seed": s}) for s in FRESH_SEEDS]
    configs += [("ais", {}), ("ycb", {})]
    for label, extra in configs:
        split = label.split()[0]
        cats = ("drill",) if split == "ais" else CATEGORIES
        for o in split_objects(BenchmarkConfig(split=split, categories=cats, instances_per_category=99,
                                               data_dir=args.data, **extra)):
            groups.setdefault((label, o.category), []).append((Path(o.model_dir), o.instance))
    for (label, category), objects in groups.items():
        angles = sorted((angle(d, n), n) for d, n in objects)
        print(f"{label:18s} {category:13s} {len(angles):3d} objects; lowest: "
              + ", ".join(f"{n} {a:.1f} deg" for a, n in angles[:3]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
