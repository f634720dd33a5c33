"""Would a drill shape space trained on generated AND real drills complete real drills better? (issue 19)

    python benchmarks/bench_joint_space.py [--seed 0] [--quick]

Three shape spaces, all with the committed drill model's settings (its
canonical drill, CPD kernel beta and lambda, variance kept) and the same
canonical -> instance registrations (the committed model's own for the
generated drills, one CPD each for the real ones):

* ``generated``: the committed model's space (its 11 generated drills);
* ``real``: the canonical generated drill + the real drills of the fold;
* ``joint``: the 11 generated drills + the real drills of the fold.

Leave-one-out over the 11 real drill clouds of the paper's authors
(``../shared/datasets/ais_drills``; skipped when absent): the held-out drill
is seen fully and from 4 side views (as ``bench_real_drills.py``: camera
0.6 m away at 30 deg elevation, azimuths 0/90/180/270, hidden-point removal,
a seeded yaw <= 15 deg and shift <= 2 cm) and fitted as the product fits
(visibility-aware latent fit, 8-start yaw search). Also fitted by the
``generated`` and ``joint`` (all 11 real drills) spaces, from the same kinds
of views: the data set's 2 held-out generated drills (drill_11, drill_12),
and the YCB 035 power drill when ``out/ycb`` holds it
(``python -m catgrasp_drake.data.ycb --out out/ycb``).

Printed per space and object group: full-view Chamfer (mm), the fit's
confidence and scale on the full view, partial-view Chamfer and the error
on the part each view does not see (mm; mean distance from the hidden true
points to the completed shape). Measures; trains and tunes nothing.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "benchmarks"))

from bench_real_drills import DRILLS, chamfer, load_drills, make_views  # noqa: E402

from catgrasp_drake.category_model import CategoryModel  # noqa: E402
from catgrasp_drake.core.cpd import nonrigid_cpd  # noqa: E402
from catgrasp_drake.core.inference import infer_latent_pose  # noqa: E402
from catgrasp_drake.core.shape_space import build_shape_space  # noqa: E402
from catgrasp_drake.data.dataset import instance_clouds  # noqa: E402
from catgrasp_drake.data.meshes import read_mesh  # noqa: E402
from catgrasp_drake.data.pointclouds import full_cloud  # noqa: E402
from catgrasp_drake.demo import default_model_path  # noqa: E402

VOXEL = 0.01  # the training clouds' voxel grid (TrainingConfig.cloud_voxel)
HELD_OUT_GENERATED = ("drill_11", "drill_12")


def fit(space, view):
    """(full-view Chamfer or partial Chamfer, unseen error or nan, confidence, scale) of one view, mm."""
    r = infer_latent_pose(space, view["obs"], camera_position=view["camera"], yaw_candidates=8)
    c = r.completed
    unseen = cKDTree(c).query(view["hidden"])[0].mean() * 1e3 if len(view["hidden"]) else np.nan
    return chamfer(c, view["gt"]) * 1e3, unseen, r.confidence, r.s


def summarize(rows):
    """Mean full Chamfer, median confidence and scale (full views), mean partial Chamfer and unseen error."""
    full = [r for r in rows if r[0] == "full"]
    part = [r for r in rows if r[0] == "partial"]
    return (np.mean([r[1] for r in full]), np.median([r[3] for r in full]), np.median([r[4] for r in full]),
            np.mean([r[1] for r in part]), np.mean([r[2] for r in part]))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--quick", action="store_true", help="3 real test drills only")
    args = ap.parse_args(argv)
    if not DRILLS.is_dir():
        print(f"skipped: {DRILLS} is absent")
        return 0
    t0 = time.perf_counter()
    model = CategoryModel.load(default_model_path("drill"), category="drill")
    gen = model.space
    kw = dict(beta=gen.beta, lam=gen.lam, variance=gen.variance, w=gen.w)
    c = gen.canonical_index
    gen_clouds = instance_clouds("drill", model.instances, VOXEL)
    names, real = load_drills()
    canonical = gen_clouds[c]
    W_real = [nonrigid_cpd(canonical, T, beta=gen.beta, lam=gen.lam, w=gen.w).W for T in real]

    def space_of(gen_idx, real_idx):
        clouds = [gen_clouds[i] for i in gen_idx] + [real[i] for i in real_idx]
        ci = gen_idx.index(c)
        reg = {(ci, k): gen.W_train[i] for k, i in enumerate(gen_idx) if i != c}
        reg.update({(ci, len(gen_idx) + k): W_real[i] for k, i in enumerate(real_idx)})
        return build_shape_space(clouds, canonical_index=ci, registrations=reg, **kw)

    all_gen = list(range(len(gen_clouds)))
    rng = np.random.default_rng(args.seed)
    results = {}  # (space, group) -> rows (kind, chamfer, unseen, confidence, scale)
    qs = {}
    tests = range(len(real)) if not args.quick else range(0, len(real), 4)
    for k in tests:
        others = [i for i in range(len(real)) if i != k]
        spaces = {"generated": gen, "real": space_of([c], others), "joint": space_of(all_gen, others)}
        for name, s in spaces.items():
            qs.setdefault(name, set()).add(s.q)
        for view in make_views(real[k], rng):
            for name, s in spaces.items():
                ch, un, conf, sc = fit(s, view)
                results.setdefault((name, "real drills (left out)"), []).append(
                    ("full" if view["az"] is None else "partial", ch, un, conf, sc))
        print(f"  real {names[k]} done ({time.perf_counter() - t0:.0f} s)", file=sys.stderr, flush=True)
    others = list(range(len(real)))
    joint_all = space_of(all_gen, others)
    qs.setdefault("joint (all 11 real)", set()).add(joint_all.q)
    extra = {f"generated {n}": instance_clouds("drill", [n], VOXEL)[0] for n in HELD_OUT_GENERATED}
    ycb = REPO / "out" / "ycb" / "drill" / "ycb_035" / "ycb_035.obj"
    if ycb.is_file():
        extra["YCB 035"] = full_cloud(read_mesh(ycb), voxel=0.005)
    for label, T in extra.items():
        group = "YCB 035" if label.startswith("YCB") else "held-out generated drills"
        for view in make_views(T, rng):
            for name, s in (("generated", gen), ("joint", joint_all)):
                ch, un, conf, sc = fit(s, view)
                results.setdefault((name, group), []).append(
                    ("full" if view["az"] is None else "partial", ch, un, conf, sc))
    print(f"Drill shape spaces on real drills (leave-one-out over {len(list(tests))} of {len(real)} AIS clouds) and "
          f"held-out objects; committed settings (beta {gen.beta} m, lambda {gen.lam}, variance {gen.variance}); "
          f"q: " + ", ".join(f"{n} {min(v)}-{max(v)}" for n, v in qs.items()) + f"; {time.perf_counter() - t0:.0f} s")
    print()
    print("| objects | space | full: Chamfer (mm) | full: confidence | full: scale | partial: Chamfer (mm) "
          "| partial: unseen part (mm) |")
    print("|---|---|---:|---:|---:|---:|---:|")
    for (name, group), rows in results.items():
        f_ch, conf, sc, p_ch, un = summarize(rows)
        print(f"| {group} | {name} | {f_ch:.2f} | {conf:.2f} | {sc:.2f} | {p_ch:.2f} | {un:.2f} |")
    return 0


if __name__ == "__main__":
    from catgrasp_drake.errors import run_script

    raise SystemExit(run_script(main))
