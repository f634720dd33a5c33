"""Contact sheets of the embedded data set (README pictures)."""

from __future__ import annotations

import os

import numpy as np

from catgrasp_drake.data.dataset import CATEGORIES, instance_mesh_path, list_instances, load_annotations
from catgrasp_drake.viz.render import contact_sheet, render_mesh

_COLORS = {"drill": (0.85, 0.45, 0.1, 1.0), "spray_bottle": (0.25, 0.5, 0.85, 1.0), "mug": (0.8, 0.8, 0.75, 1.0)}


def dataset_contact_sheet(path: str | os.PathLike, *, categories=None, tile: int = 200, columns: int = 9) -> None:
    """Render every instance of ``categories`` (default: all) into one PNG, one row block per category.

    Tiles of one category share a scale so relative sizes are visible.
    """
    images, labels = [], []
    for category in categories or CATEGORIES:
        names = list_instances(category)
        lo = np.min([load_annotations(category, n)["bbox_min"] for n in names], axis=0)
        hi = np.max([load_annotations(category, n)["bbox_max"] for n in names], axis=0)
        center = (lo + hi) / 2
        for name in names:
            bounds = (center - (hi - lo) / 2, center + (hi - lo) / 2)
            images.append(render_mesh(instance_mesh_path(category, name), color=_COLORS[category],
                                      size=(tile, tile), bounds=bounds))
            labels.append(name)
        while len(images) % columns:  # start each category on a new row
            images.append(np.full_like(images[-1], 255))
            labels.append("")
    contact_sheet(images, labels, path, columns=columns)
