"""Write shrouded copies of the deep committed spray bottles (``data.stretch.shrouded_instance``): a tuning set
with the YCB Windex bottle's head.

    python benchmarks/results/experiments/s41_windex_thumb/make_shrouded.py OUT_DIR
    python diagrams/hand_fit.py --objects OUT_DIR/* --closing [--grasp FILE]
    python diagrams/handwritten_sweep.py --objects OUT_DIR/* [--grasp FILE] [--placements N]
    catgrasp search-grasp --category spray_bottle --objects OUT_DIR/* ...

Every deep committed bottle (generator parameter ``deep``), its head's back hung down behind the neck to 5 mm
above its trigger's centre; written as ``OUT_DIR/<instance>_shroud``.
"""

from __future__ import annotations

import sys
from pathlib import Path

from catgrasp_drake.data.dataset import list_instances, load_annotations
from catgrasp_drake.data.stretch import shrouded_instance


def main(out: str) -> None:
    for name in list_instances("spray_bottle"):
        if load_annotations("spray_bottle", name)["params"].get("deep"):
            written = shrouded_instance(name, Path(out) / f"{name}_shroud")
            print(f"{written.name}: {written.mass_kg:.3f} kg -> {written.directory}")


if __name__ == "__main__":
    main(sys.argv[1])
