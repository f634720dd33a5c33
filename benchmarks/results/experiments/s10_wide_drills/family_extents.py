"""How close the drill generator's family comes to each real drill, by bounding-box extents (no simulation).

    python benchmarks/results/experiments/s10_wide_drills/family_extents.py [--draws 300]

Draws ``--draws`` drills from ``categories.drill_params`` (seeds [0, i]) and prints, for each real drill
(the 11 AIS clouds in ../shared/datasets/ais_drills, the YCB drill in out/ycb when prepared), the
smallest largest-relative-extent difference to any drawn drill and how many lie within 8 %. Run it as
committed (the committed family) and with wide_drills.diff applied (the widened one).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[4]
sys.path.insert(0, str(ROOT))

from catgrasp_drake.data.categories import DENSITY_KG_M3, build_drill, drill_params  # noqa: E402
from catgrasp_drake.data.meshes import read_mesh  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=300)
    args = ap.parse_args(argv)
    real = {p.stem: np.loadtxt(p, skiprows=11)[:, :3]
            for p in sorted((ROOT.parent / "shared" / "datasets" / "ais_drills").glob("drill_*.pcd"),
                            key=lambda p: int(p.stem.split("_")[1]))}
    ycb = ROOT / "out" / "ycb" / "drill" / "ycb_035" / "ycb_035.obj"
    if ycb.is_file():
        real["ycb_035"] = np.asarray(read_mesh(ycb).vertices)
    drills = [build_drill(drill_params(np.random.default_rng([0, i]))) for i in range(args.draws)]
    E = np.array([d.mesh.extents for d in drills])
    mass = np.array([d.mesh.volume * DENSITY_KG_M3["drill"] for d in drills])
    ranges = ", ".join(f"{ax} {E[:, i].min():.3f}-{E[:, i].max():.3f}" for i, ax in enumerate("xyz"))
    print(f"{args.draws} drills: extents {ranges} m; mass {mass.min():.2f}-{mass.max():.2f} kg")
    for name, points in real.items():
        r = points.max(axis=0) - points.min(axis=0)
        d = (np.abs(E - r) / r).max(axis=1)
        print(f"{name:10s} {np.round(r, 3)}  nearest drawn drill: {100 * d.min():4.1f} %   "
              f"within 8 %: {(d < 0.08).sum()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
