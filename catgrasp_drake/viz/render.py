"""Headless mesh rendering with Drake's RenderEngineVtk, and contact sheets.

Used for the README's pictures. No display is needed: RenderEngineVtk renders
offscreen. Meshes must be ``.obj`` files with normals.
"""

from __future__ import annotations

import io
import os
from pathlib import Path
from typing import Sequence

import numpy as np
import trimesh
from PIL import Image, ImageDraw
from pydrake.geometry import (
    ClippingRange,
    ColorRenderCamera,
    GeometryInstance,
    MakeRenderEngineVtk,
    Mesh,
    PerceptionProperties,
    RenderCameraCore,
    RenderEngineVtkParams,
    RenderLabel,
    Rgba,
    SceneGraph,
)
from pydrake.math import RigidTransform
from pydrake.systems.sensors import CameraInfo

from catgrasp_drake.core.fileio import atomic_write_bytes
from catgrasp_drake.core.visibility import camera_on_sphere_position, look_at_matrix

_RENDERER = "catgrasp_vtk"


def render_mesh(
    mesh_path: str | os.PathLike,
    *,
    color=(0.55, 0.6, 0.7, 1.0),
    size: tuple[int, int] = (320, 320),
    azimuth_deg: float = 35.0,
    elevation_deg: float = 20.0,
    fov_y_deg: float = 30.0,
    bounds: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """Render one mesh (in its own frame) to an RGB uint8 image of ``size`` (w, h).

    The camera looks at the bounding-box centre from the +x side, rotated by
    ``azimuth_deg`` about z toward -y and raised by ``elevation_deg``, so the
    object's +y (functional direction) points right in the image.
    """
    if bounds is None:
        m = trimesh.load(str(mesh_path), force="mesh")
        bounds = (m.bounds[0], m.bounds[1])
    lo, hi = (np.asarray(b, float) for b in bounds)
    center = (lo + hi) / 2
    radius = 0.5 * np.linalg.norm(hi - lo)
    dist = 1.15 * radius / np.sin(np.radians(fov_y_deg) / 2)
    az, el = np.radians(azimuth_deg), np.radians(elevation_deg)
    eye = camera_on_sphere_position(center, dist, -az, el)  # azimuth toward -y: +y points right

    scene_graph = SceneGraph()
    scene_graph.AddRenderer(_RENDERER, MakeRenderEngineVtk(RenderEngineVtkParams(default_clear_color=[1.0, 1.0, 1.0])))
    source = scene_graph.RegisterSource("render_mesh")
    geometry = GeometryInstance(RigidTransform(), Mesh(str(mesh_path)), Path(mesh_path).stem)
    props = PerceptionProperties()
    props.AddProperty("phong", "diffuse", Rgba(*color))
    props.AddProperty("label", "id", RenderLabel(1))
    gid = scene_graph.RegisterAnchoredGeometry(source, geometry)
    scene_graph.AssignRole(source, gid, props)
    context = scene_graph.CreateDefaultContext()
    query = scene_graph.get_query_output_port().Eval(context)
    return render_color(query, scene_graph.world_frame_id(), eye, center, size, fov_y_deg)


def render_color(query, frame_id, eye, target, size: tuple[int, int], fov_y_deg: float, *,
                 renderer: str = _RENDERER, far: float = 10.0) -> np.ndarray:
    """(H, W, 3) uint8 colour image of a SceneGraph ``query`` object from a camera at ``eye`` (m, in the frame
    ``frame_id``) looking at ``target``, with the renderer named ``renderer``."""
    w, h = size
    core = RenderCameraCore(renderer, CameraInfo(w, h, np.radians(fov_y_deg)), ClippingRange(0.01, far),
                            RigidTransform())
    X_WC = RigidTransform(look_at_matrix(eye, target))
    image = query.RenderColorImage(ColorRenderCamera(core, False), frame_id, X_WC)
    return rgb_array(image)


def rgb_array(image) -> np.ndarray:
    """A Drake ``ImageRgba8U`` as an (H, W, 3) uint8 array (a copy)."""
    return np.array(image.data, copy=True)[:, :, :3]


def contact_sheet(
    images: Sequence[np.ndarray],
    labels: Sequence[str],
    path: str | os.PathLike,
    *,
    columns: int = 6,
    title: str | None = None,
) -> None:
    """Tile RGB images with labels into one PNG written atomically to ``path``."""
    if not images:
        raise ValueError("contact_sheet: no images")
    h, w = images[0].shape[:2]
    rows = (len(images) + columns - 1) // columns
    top = 24 if title else 0
    sheet = Image.new("RGB", (columns * w, rows * (h + 16) + top), "white")
    draw = ImageDraw.Draw(sheet)
    if title:
        draw.text((6, 6), title, fill="black")
    for k, (img, label) in enumerate(zip(images, labels)):
        r, c = divmod(k, columns)
        x, y = c * w, top + r * (h + 16)
        sheet.paste(Image.fromarray(img), (x, y))
        draw.text((x + 4, y + h + 2), label, fill="black")
    buf = io.BytesIO()
    sheet.save(buf, format="PNG", optimize=True)
    atomic_write_bytes(path, buf.getvalue())
