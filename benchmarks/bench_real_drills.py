"""Shape completion accuracy on the 11 real drills (leave-one-out), DESIGN.md section 9 protocol.

For each drill: a shape space from the other 10 (canonical chosen automatically
by reconstruction energy among them), then the held-out drill is observed

* fully (the whole cloud), and
* from 4 single views (camera 0.6 m from the centre, 30 deg elevation,
  azimuths 0/90/180/270 deg, hidden-point removal),

each observation moved by a seeded unknown yaw <= 15 deg and shift <= 2 cm
(in x, y). Every method starts from centroid matching (of the part of the
model the camera would see, when the camera is known). Errors in mm:

* Chamfer: symmetric, mean of the two mean nearest-neighbour distances between
  the completed shape and the full ground-truth cloud;
* unseen: mean distance from the ground-truth points hidden in that view to
  the completed shape (what completion is for).

Run:  python benchmarks/bench_real_drills.py            (about 2-3 min on 2 cores)
      python benchmarks/bench_real_drills.py --quick    (3 test drills)
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

from catgrasp_drake.core.cpd import nonrigid_cpd, rigid_cpd  # noqa: E402
from catgrasp_drake.core.inference import infer_latent_pose  # noqa: E402
from catgrasp_drake.core.rotations import rotz  # noqa: E402
from catgrasp_drake.core.shape_space import build_shape_space  # noqa: E402
from catgrasp_drake.core.visibility import camera_on_sphere_position, hidden_point_removal  # noqa: E402

DRILLS = REPO.parent / "shared" / "datasets" / "ais_drills"
AZIMUTHS_DEG = (0, 90, 180, 270)


def load_drills():
    paths = sorted(DRILLS.glob("drill_*.pcd"), key=lambda p: int(p.stem.split("_")[1]))
    if not paths:
        raise SystemExit(f"no drills found in {DRILLS}")
    return [p.stem for p in paths], [np.loadtxt(p, skiprows=11)[:, :3] for p in paths]


def chamfer(A, B):
    return 0.5 * (cKDTree(B).query(A)[0].mean() + cKDTree(A).query(B)[0].mean())


def make_views(T, rng):
    """Full + 4 partial observations of T, each moved by a random yaw/shift: list of dicts."""
    c = T.mean(axis=0)
    views = []
    for az in (None,) + AZIMUTHS_DEG:
        yaw = rng.uniform(-np.radians(15), np.radians(15))
        shift = np.r_[rng.uniform(-0.02, 0.02, 2), 0.0]
        Rz = rotz(yaw)

        def move(p):
            return (p - c) @ Rz.T + c + shift

        if az is None:
            vis = np.ones(len(T), dtype=bool)
            cam = None
        else:
            cam0 = camera_on_sphere_position(c, 0.6, np.radians(az), np.radians(30))
            vis = hidden_point_removal(T, cam0)
            cam = move(cam0[None])[0]
        views.append({"az": az, "obs": move(T[vis]), "gt": move(T), "hidden": move(T[~vis]), "camera": cam})
    return views


def start_translation(canonical, obs, camera):
    """Centroid matching (of the camera-visible part of the canonical, when a camera is given)."""
    t = obs.mean(0) - canonical.mean(0)
    if camera is not None:
        vis = hidden_point_removal(canonical + t, camera)
        t = obs.mean(0) - canonical[vis].mean(0)
    return t


def run_methods(space, view, methods):
    C = space.canonical
    obs, cam = view["obs"], view["camera"]
    out = {}
    for name in methods:
        t0 = time.perf_counter()
        if name == "observation":
            completed = obs
        elif name == "rigid":
            r = rigid_cpd(C + start_translation(C, obs, cam), obs, scale=False, w=0.05)
            completed = r.transformed
        elif name == "rigid+scale":
            r = rigid_cpd(C + start_translation(C, obs, cam), obs, scale=True, w=0.05)
            completed = r.transformed
        elif name == "direct CPD":
            r = nonrigid_cpd(C + start_translation(C, obs, cam), obs, beta=space.beta, lam=space.lam, w=0.05)
            completed = r.transformed
        elif name == "latent (no visibility)":
            completed = infer_latent_pose(space, obs).completed
        elif name == "latent":
            completed = infer_latent_pose(space, obs, camera_position=cam).completed
        elif name == "latent + residual CPD":
            completed = infer_latent_pose(space, obs, camera_position=cam, residual_cpd=True).completed
        elif name == "latent, yaw search x8":
            completed = infer_latent_pose(space, obs, camera_position=cam, yaw_candidates=8).completed
        else:
            raise ValueError(name)
        dt = time.perf_counter() - t0
        ch = chamfer(completed, view["gt"])
        unseen = cKDTree(completed).query(view["hidden"])[0].mean() if len(view["hidden"]) else np.nan
        out[name] = (ch * 1e3, unseen * 1e3, dt)
    return out


METHODS = [
    "observation",
    "rigid",
    "rigid+scale",
    "direct CPD",
    "latent (no visibility)",
    "latent",
    "latent + residual CPD",
    "latent, yaw search x8",
]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="only 3 test drills")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    names, drills = load_drills()
    K = len(drills)
    rng = np.random.default_rng(args.seed)
    t0 = time.perf_counter()
    # all pairwise CPD registrations once (reused by every fold's canonical selection)
    from catgrasp_drake.core.cpd import DEFAULT_BETA_M, DEFAULT_LAMBDA

    pairs = {}
    for c in range(K):
        for i in range(K):
            if i != c:
                pairs[(c, i)] = nonrigid_cpd(drills[c], drills[i], beta=DEFAULT_BETA_M, lam=DEFAULT_LAMBDA).W
    t_pairs = time.perf_counter() - t0
    tests = range(K) if not args.quick else range(0, K, 4)
    rows = {m: {"full": [], "partial": [], "unseen": [], "time": []} for m in METHODS}
    wins = {m: 0 for m in METHODS}
    n_partial = 0
    qs = []
    for test in tests:
        train_idx = [i for i in range(K) if i != test]
        reg = {(a, b): pairs[(train_idx[a], train_idx[b])] for a in range(K - 1) for b in range(K - 1) if a != b}
        space = build_shape_space([drills[i] for i in train_idx], canonical_index="auto", registrations=reg)
        qs.append(space.q)
        for view in make_views(drills[test], rng):
            res = run_methods(space, view, METHODS)
            for m, (ch, un, dt) in res.items():
                rows[m]["time"].append(dt)
                if view["az"] is None:
                    rows[m]["full"].append(ch)
                else:
                    rows[m]["partial"].append(ch)
                    rows[m]["unseen"].append(un)
            if view["az"] is not None:
                n_partial += 1
                best_baseline = min(res["rigid+scale"][1], res["direct CPD"][1])
                for m in METHODS:
                    if res[m][1] < best_baseline:
                        wins[m] += 1
    total = time.perf_counter() - t0
    print(f"Real drills, leave-one-out: {len(list(tests))} test drills x (1 full + 4 partial views), "
          f"q = {min(qs)}..{max(qs)}, CPD beta={DEFAULT_BETA_M} m lambda={DEFAULT_LAMBDA}; "
          f"pairwise CPDs {t_pairs:.1f} s, total {total:.1f} s")
    print()
    print("| method | full view: Chamfer (mm) | partial: Chamfer (mm) | partial: unseen part (mm) | "
          "partial: unseen better than both baselines | median time (s) |")
    print("|---|---|---|---|---|---|")
    for m in METHODS:
        r = rows[m]
        print(f"| {m} | {np.mean(r['full']):.2f} | {np.mean(r['partial']):.2f} | {np.mean(r['unseen']):.2f} | "
              f"{wins[m]}/{n_partial} | {np.median(r['time']):.3f} |")
    print()
    for ours in ("latent", "latent + residual CPD"):
        for key, label in (("unseen", "unseen part"), ("partial", "Chamfer")):
            v = np.mean(rows[ours][key])
            print(f"partial views, {label}: rigid+scale / {ours} = {np.mean(rows['rigid+scale'][key]) / v:.2f}, "
                  f"direct CPD / {ours} = {np.mean(rows['direct CPD'][key]) / v:.2f}")


if __name__ == "__main__":
    main()
