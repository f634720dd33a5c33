"""The planner's object clearance, measured: how deep the preshaped hand starts inside each object, and how exact
the signed-distance grid is (no simulation).

    python benchmarks/bench_clearance.py [--categories drill spray_bottle mug] [--ycb out/ycb]

For every committed instance and every prepared YCB scan (``python -m
catgrasp_drake.data.ycb --out out/ycb``; skipped when absent) the category's
hand-written grasp is anchored on the object's annotation, as
``diagrams/handwritten_sweep.py`` runs it, and the preshaped hand's collision
points at the grasp pose (``planning.scene.hand_surface_points_H``, what
``planning.planner.clear_object`` checks) are measured against the object:

- depth: the deepest hand point inside the object (mm; negative: the hand's
  closest point is that far outside), by the planner's grid
  (``planning.model.true_object_field``) and by open3d's exact signed distance
  to the mesh;
- the move the clearance makes (mm; 0 within ``PlanParams.object_penetration_tol``).

Then the grid's accuracy: its signed distance against open3d's exact one at
20 000 random points within 2 cm of each mesh of ``--accuracy`` (mean, 5th and
95th percentile of the difference, mm; sign agreement).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from catgrasp_drake.core.clearance import clearance_shift  # noqa: E402
from catgrasp_drake.data.dataset import CATEGORIES, imported_object, list_instances, read_annotations  # noqa: E402
from catgrasp_drake.data.meshes import read_mesh  # noqa: E402
from catgrasp_drake.data.open3d_import import import_open3d  # noqa: E402
from catgrasp_drake.planning.model import PlanningModel, object_mesh_path, true_object_field  # noqa: E402
from catgrasp_drake.planning.records import PlanParams  # noqa: E402
from catgrasp_drake.planning.scene import hand_surface_points_H, planning_scene  # noqa: E402
from catgrasp_drake.station.handwritten import load_handwritten_motion  # noqa: E402
from catgrasp_drake.station.scenario import load_scenario, with_instance  # noqa: E402
from catgrasp_drake.trial import trial_diagram  # noqa: E402


def exact_signed_distance(mesh, points: np.ndarray) -> np.ndarray:
    """open3d's signed distance to ``mesh`` at ``points`` (m), POSITIVE INSIDE as the planner's grid."""
    o3d = import_open3d()
    scene = o3d.t.geometry.RaycastingScene()
    legacy = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(mesh.vertices),
                                       o3d.utility.Vector3iVector(mesh.faces))
    scene.add_triangles(o3d.t.geometry.TriangleMesh.from_legacy(legacy))
    return -scene.compute_signed_distance(o3d.core.Tensor(np.asarray(points, np.float32))).numpy()


def hand_points_at_grasp_O(category: str, instance: str, model_dir: str | None) -> tuple[np.ndarray, Path]:
    """The preshaped hand's collision points at the hand-written grasp, in the object frame O, and the mesh path."""
    scenario = with_instance(load_scenario(f"{category}_default"), instance, category=category, model_dir=model_dir)
    motion_W = load_handwritten_motion(category, instance, annotations_dir=model_dir).in_world(scenario.X_WO())
    td = trial_diagram(scenario)
    pm = PlanningModel.of_station(td.diagram, td.station)
    ctx = pm.diagram.CreateDefaultContext()
    c = planning_scene(pm.plant, pm.plant.GetMyMutableContextFromRoot(ctx), pm.scene_graph,
                       pm.scene_graph.GetMyMutableContextFromRoot(ctx), arm=pm.arm, hand=pm.hand,
                       object_instance=pm.obstacle, table=pm.table, q_arm_start=pm.q_arm_start,
                       q_hand=motion_W.posture("preshape"))
    M = np.linalg.inv(scenario.X_WO()) @ motion_W.pose("grasp")
    return hand_surface_points_H(c) @ M[:3, :3].T + M[:3, 3], object_mesh_path(scenario.object)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--categories", nargs="+", default=list(CATEGORIES), choices=CATEGORIES)
    ap.add_argument("--ycb", type=Path, default=ROOT / "out" / "ycb")
    ap.add_argument("--accuracy", nargs="*", default=["drill/drill_00", "mug/mug_00", "spray_bottle/spray_bottle_00",
                                                        "ycb:drill/ycb_035", "ycb:mug/ycb_025"],
                    help="meshes for the grid's accuracy: category/instance, or ycb:category/name")
    args = ap.parse_args(argv)
    params = PlanParams()
    print(f"{'object':18s} {'depth, grid (mm)':>16s} {'depth, exact (mm)':>17s} {'move (mm)':>9s}")
    for category in args.categories:
        targets = [(n, None) for n in list_instances(category)]
        if args.ycb.is_dir():
            targets += [(imported_object(d)[1], str(d)) for d in sorted((args.ycb / category).glob("ycb_*"))
                        if read_annotations(d / "annotations.json").get("regions")]  # not the trigger-less bottles
        depths = []
        for instance, model_dir in targets:
            p_O, mesh_path = hand_points_at_grasp_O(category, instance, model_dir)
            field = true_object_field(str(mesh_path))
            grid = float(field(p_O).max())
            exact = float(exact_signed_distance(read_mesh(mesh_path), p_O).max())
            move = clearance_shift(p_O, field, params.object_penetration_tol, params.max_object_shift).shift
            if model_dir is None:
                depths.append(grid)
            print(f"{instance:18s} {1000 * grid:16.1f} {1000 * exact:17.1f} {1000 * np.linalg.norm(move):9.1f}")
        print(f"{category}: deepest hand-written grasp on the committed instances {1000 * max(depths):.1f} mm "
              f"(grid); the tolerance is {1000 * params.object_penetration_tol:.0f} mm")
    print("\ngrid against exact signed distance, random points within 2 cm of the surface (mm)")
    rng = np.random.default_rng(1)
    for spec in args.accuracy:
        if spec.startswith("ycb:"):
            path = args.ycb / spec[4:] / f"{Path(spec).name}.obj"
            if not path.is_file():
                print(f"{spec}: not prepared, skipped")
                continue
        else:
            category, instance = spec.split("/")
            path = object_mesh_path(with_instance(load_scenario(f"{category}_default"), instance,
                                                  category=category).object)
        mesh = read_mesh(path)
        lo, hi = mesh.bounds
        q = rng.uniform(lo - 0.01, hi + 0.01, size=(20000, 3))
        exact = exact_signed_distance(mesh, q)
        near = np.abs(exact) < 0.02
        err = true_object_field(str(path))(q[near]) - exact[near]
        agree = np.mean((true_object_field(str(path))(q) > 0) == (exact > 0))
        print(f"{spec:28s} mean {1000 * err.mean():+.2f}  p5 {1000 * np.percentile(err, 5):+.2f}  "
              f"p95 {1000 * np.percentile(err, 95):+.2f}  sign agreement {agree:.3f}")
    return 0


if __name__ == "__main__":
    from catgrasp_drake.errors import run_script

    raise SystemExit(run_script(main))
