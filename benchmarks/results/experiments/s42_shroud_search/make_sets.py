"""Session 42: the tuning bottles of the shroud search, written under OUT (default ``out/s42``).

    python benchmarks/results/experiments/s42_shroud_search/make_sets.py [OUT]

- ``OUT/val_objects/spray_bottle_val_NN``: the validation split's bottles renamed (session 38's ``copy_val.py``);
- ``OUT/shroud/spray_bottle_NN_shroud``: the deep committed bottles with the Windex head (session 41);
- ``OUT/shroud_val/spray_bottle_val_NN_shroud``: the deep validation bottles with the Windex head.

Every one is a tuning object: committed instances, the validation split (seed 902870906) and copies of them.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[4]
sys.path.insert(0, str(ROOT))


def main(out: str = str(ROOT / "out" / "s42")) -> None:
    import importlib.util

    from catgrasp_drake.data.dataset import list_instances, load_annotations, read_annotations
    from catgrasp_drake.data.stretch import shrouded_instance

    out = Path(out)
    spec = importlib.util.spec_from_file_location(
        "copy_val", ROOT / "benchmarks/results/experiments/s38_spray_val_grasp/copy_val.py")
    copy_val = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(copy_val)
    copy_val.main(["--out", str(out / "val_objects")])
    for name in list_instances("spray_bottle"):
        if load_annotations("spray_bottle", name)["params"].get("deep"):
            print(shrouded_instance(name, out / "shroud" / f"{name}_shroud").directory)
    for bottle in sorted(p for p in (out / "val_objects").iterdir() if p.is_dir()):
        if read_annotations(bottle / "annotations.json")["params"].get("deep"):
            print(shrouded_instance(bottle, out / "shroud_val" / f"{bottle.name}_shroud").directory)


if __name__ == "__main__":
    main(*sys.argv[1:2])
