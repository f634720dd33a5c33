"""Headless pictures of the robot models (Drake RenderEngineVtk, no display needed).

Run as::

    python -m tools.render_hand --out docs/hand.png --arm-out docs/arm_hand.png

``docs/hand.png`` shows the SVH hand from four viewpoints (open and in the
cylinder "closed" posture, palm side and back side); ``docs/arm_hand.png``
shows the UR10 with the hand in its home configuration.
"""

from __future__ import annotations

import argparse
import io
import sys
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw
from pydrake.geometry import (
    MakeRenderEngineVtk,
    RenderEngineVtkParams,
)
from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlantConfig
from pydrake.systems.framework import DiagramBuilder

from catgrasp_drake.core.fileio import atomic_write_bytes
from catgrasp_drake.robot import models
from catgrasp_drake.viz.render import render_color

_RENDERER = "robot_vtk"


def _build(with_arm: bool):
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlant(
        MultibodyPlantConfig(time_step=5e-3, discrete_contact_approximation="sap"), builder
    )
    scene_graph.AddRenderer(
        _RENDERER, MakeRenderEngineVtk(RenderEngineVtkParams(default_clear_color=[1.0, 1.0, 1.0]))
    )
    if with_arm:
        parts = models.add_arm_and_hand(plant)
        hand = parts.hand
        arm = parts.arm
    else:
        hand = models.add_hand(plant)
        plant.WeldFrames(plant.world_frame(), plant.GetFrameByName(models.HAND_BASE_LINK, hand))
        arm = None
    plant.Finalize()
    diagram = builder.Build()
    return diagram, plant, scene_graph, hand, arm


def _render(diagram, scene_graph, context, eye, target, size=(480, 480), fov_deg=35.0) -> np.ndarray:
    query = scene_graph.get_query_output_port().Eval(scene_graph.GetMyContextFromRoot(context))
    return render_color(query, scene_graph.world_frame_id(), eye, target, size, fov_deg, renderer=_RENDERER, far=20.0)


def _sheet(images, labels, columns: int) -> bytes:
    h, w = images[0].shape[:2]
    rows = (len(images) + columns - 1) // columns
    sheet = Image.new("RGB", (columns * w, rows * (h + 18)), "white")
    draw = ImageDraw.Draw(sheet)
    for k, (img, label) in enumerate(zip(images, labels)):
        r, c = divmod(k, columns)
        sheet.paste(Image.fromarray(img), (c * w, r * (h + 18)))
        draw.text((c * w + 6, r * (h + 18) + h + 3), label, fill="black")
    buf = io.BytesIO()
    sheet.save(buf, format="PNG", optimize=True)
    return buf.getvalue()


def render_hand_picture() -> bytes:
    diagram, plant, scene_graph, hand, _ = _build(with_arm=False)
    context = diagram.CreateDefaultContext()
    plant_context = plant.GetMyContextFromRoot(context)
    postures = models.load_hand_postures("cylinder")
    target = np.array([-0.01, 0.01, 0.10])
    views = [
        ("open, palm side (+y)", postures["open"], target + [0.10, 0.42, 0.10]),
        ("open, back side (-y)", postures["open"], target + [0.12, -0.42, 0.10]),
        ("cylinder preshape, from the thumb side", postures["preshape"], target + [-0.38, 0.25, 0.08]),
        ("cylinder closed (no object)", postures["closed"], target + [0.36, 0.28, 0.0]),
    ]
    images, labels = [], []
    for label, q, eye in views:
        models.set_hand_angles(plant, plant_context, hand, q)
        images.append(_render(diagram, scene_graph, context, eye, target))
        labels.append(f"SVH hand: {label}")
    return _sheet(images, labels, columns=2)


def render_arm_hand_picture() -> bytes:
    diagram, plant, scene_graph, hand, arm = _build(with_arm=True)
    context = diagram.CreateDefaultContext()
    plant_context = plant.GetMyContextFromRoot(context)
    plant.SetPositions(plant_context, arm, models.ARM_HOME_POSITIONS)
    models.set_hand_angles(plant, plant_context, hand, models.load_hand_postures("cylinder")["preshape"])
    images = [
        _render(diagram, scene_graph, context, [1.2, -1.5, 1.1], [-0.5, -0.15, 0.4], size=(640, 560), fov_deg=45.0),
        _render(diagram, scene_graph, context, [-1.9, 1.5, 1.4], [-0.5, -0.15, 0.4], size=(640, 560), fov_deg=45.0),
    ]
    labels = ["UR10 + SVH, home configuration", "UR10 + SVH, home configuration (other side)"]
    return _sheet(images, labels, columns=2)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="docs/hand.png", help="PNG of the hand")
    ap.add_argument("--arm-out", default="docs/arm_hand.png", help="PNG of arm + hand ('' to skip)")
    args = ap.parse_args(argv)
    atomic_write_bytes(Path(args.out), render_hand_picture())
    sys.stdout.write(f"wrote {args.out}\n")
    if args.arm_out:
        atomic_write_bytes(Path(args.arm_out), render_arm_hand_picture())
        sys.stdout.write(f"wrote {args.arm_out}\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
