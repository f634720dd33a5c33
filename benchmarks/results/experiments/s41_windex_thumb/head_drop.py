"""How far above the trigger the head's back begins: the Windex bottle against the generator's bottles.

    python benchmarks/results/experiments/s41_windex_thumb/head_drop.py DIR [DIR ...]

Each DIR is an instance directory (annotations.json and one .obj in the canonical frame: z up, nozzle +y).
Horizontal sections of the mesh (trimesh) every 2 mm from the top down: the head's underside at the back is
the highest height below which the object no longer reaches 28 mm behind its axis (y <= -28 mm), found
descending from the top. Printed: that height minus the trigger region's centre height (mm). Geometry only.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import trimesh

from catgrasp_drake.data.meshes import back_overhang_underside_m

BACK_REACH_M = 0.028
STEP_M = 0.002


def set_of(directory: Path) -> str:
    """Which set an instance directory belongs to, from its path."""
    text = str(directory)
    for key, name in (("val_seed", "val"), ("stress", "stress"), ("ycb", "ycb"), ("models/objects", "committed")):
        if key in text:
            return name
    return "other"


def head_clearance_mm(directory: Path) -> tuple[float, float]:
    """(head underside at the back - trigger centre, trigger centre height), both in mm."""
    annotations = json.loads((directory / "annotations.json").read_text())
    trigger_z = annotations["regions"]["trigger"]["center"][2]
    mesh = trimesh.load(next(directory.glob("*.obj")), force="mesh")
    underside = back_overhang_underside_m(mesh, BACK_REACH_M, STEP_M)
    return 1000 * (underside - trigger_z), 1000 * trigger_z


def main(directories: list[str]) -> None:
    values = []
    for directory in map(Path, directories):
        clearance, trigger_z = head_clearance_mm(directory)
        values.append(clearance)
        print(f"{set_of(directory):10s} {directory.name:26s} trigger z {trigger_z:6.1f} mm   "
              f"head's back begins {clearance:6.1f} mm above it")
    generated = np.array([v for v, d in zip(values, directories) if set_of(Path(d)) != "ycb"])
    print(f"{len(generated)} generated objects: {np.isnan(generated).sum()} heads never reach "
          f"{1000 * BACK_REACH_M:.0f} mm back; the others min {np.nanmin(generated):.1f}, "
          f"median {np.nanmedian(generated):.1f}, max {np.nanmax(generated):.1f} mm")


if __name__ == "__main__":
    main(sys.argv[1:])
