"""A spray bottle's shoulder in horizontal sections under its top: reach behind / in front of the neck's axis
and half-width (cm) (session 17; the table in docs/data.md, "Domed shoulders").

    python benchmarks/results/experiments/s17_windex/sections.py

(needs the YCB scans: python -m catgrasp_drake.data.ycb --out out/ycb)

Rows: the YCB Windex bottle (its shoulder's top at z 0.19 m and its neck's axis at y -0.003 m, read off its
sections), generated spray_bottle_10 as committed before session 17 (``git show ac35059~1:...``, straight
shoulder) and as committed now (domed), both at their own ``body_height`` and ``neck_offset_y``.
"""
import io
import subprocess

import trimesh

from catgrasp_drake.data.dataset import instance_mesh_path, load_annotations


def row(mesh, top, axis_y):
    cells = []
    for below in (0.0, 0.01, 0.02, 0.03, 0.04):
        v = mesh.section(plane_origin=[0, 0, top - below + 1e-4], plane_normal=[0, 0, 1]).vertices
        cells.append(f"{100 * (axis_y - v[:, 1].min()):.1f} / {100 * (v[:, 1].max() - axis_y):.1f} / "
                     f"{50 * (v[:, 0].max() - v[:, 0].min()):.1f}")
    return " | ".join(cells)


print("under the shoulder's top | 0 cm | 1 cm | 2 cm | 3 cm | 4 cm")
windex = trimesh.load("out/ycb/spray_bottle/ycb_022/ycb_022.obj", force="mesh")
print("Windex bottle |", row(windex, 0.19, -0.003))
p = load_annotations("spray_bottle", "spray_bottle_10")["params"]
old = subprocess.run(["git", "show", "ac35059~1:models/objects/spray_bottle/spray_bottle_10/spray_bottle_10.obj"],
                     capture_output=True, check=True).stdout
print("spray_bottle_10, session 16 |", row(trimesh.load(io.BytesIO(old), file_type="obj", force="mesh"),
                                            p["body_height"], p["neck_offset_y"]))
print("spray_bottle_10, session 17 |", row(trimesh.load(instance_mesh_path("spray_bottle", "spray_bottle_10"),
                                                        force="mesh"), p["body_height"], p["neck_offset_y"]))
