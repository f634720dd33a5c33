"""Handle sections, sizes and masses of drills: generated (committed, test split), YCB and the AIS imports.

    python benchmarks/results/experiments/s19_drill_handles/handles.py [--objects DIR ...]

For each drill: height, length (y extent), mass, and the handle's horizontal section 1.5 cm under the
trigger region's bottom -- its width (x) and depth (y) -- the connected part of the section nearest the
point 1 cm behind the trigger box. Committed drills from models/objects; ``--objects`` adds imported
objects (each folder: <name>.obj, <name>.sdf, annotations.json). A measurement, no simulation.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import trimesh

from catgrasp_drake.data.dataset import instance_dir, list_instances, read_annotations


def handle_section(mesh: trimesh.Trimesh, trigger: dict, below: float = 0.015) -> tuple[float, float]:
    """Width (x) and depth (y) of the handle's horizontal section ``below`` under the ``trigger`` box (m)."""
    lo = np.asarray(trigger["center"]) - np.asarray(trigger["half_extents"])
    hi = np.asarray(trigger["center"]) + np.asarray(trigger["half_extents"])
    z = lo[2] - below
    path = mesh.section(plane_origin=[0, 0, z], plane_normal=[0, 0, 1])
    if path is None:
        return np.nan, np.nan
    probe = np.array([0.5 * (lo[0] + hi[0]), lo[1] - 0.01, z])
    # the closed outline with a vertex nearest the probe (the handle's, not the battery's)
    pts = min(path.discrete, key=lambda loop: np.min(np.linalg.norm(loop - probe, axis=1)))
    return float(np.ptp(pts[:, 0])), float(np.ptp(pts[:, 1]))


def measure(directory: Path) -> dict:
    name = directory.name
    mesh = trimesh.load(directory / f"{name}.obj", force="mesh")
    ann = read_annotations(directory / "annotations.json")
    w, d = handle_section(mesh, ann["regions"]["trigger"])
    return {"name": name, "height": mesh.extents[2], "length": mesh.extents[1], "mass": ann["mass_kg"],
            "handle_w": w, "handle_d": d}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--objects", nargs="*", default=[])
    ap.add_argument("--no-committed", action="store_true")
    a = ap.parse_args()
    dirs = [] if a.no_committed else [instance_dir("drill", i) for i in list_instances("drill")]
    dirs += [Path(d) for d in a.objects]
    print(f"{'drill':<16}{'height mm':>10}{'length mm':>10}{'mass kg':>9}{'handle w mm':>12}{'handle d mm':>12}")
    for d in dirs:
        r = measure(Path(d))
        print(f"{r['name']:<16}{1000 * r['height']:>10.0f}{1000 * r['length']:>10.0f}{r['mass']:>9.2f}"
              f"{1000 * r['handle_w']:>12.1f}{1000 * r['handle_d']:>12.1f}")


if __name__ == "__main__":
    main()
