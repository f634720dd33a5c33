"""Stretched copies of the committed instances: a tuning set with real objects' proportions.

The committed instances (``models/objects``) are where grasps, kernels and
thresholds are tuned, and the generator's family is narrower than real
objects (DESIGN.md section 4; real drills: handles 22-46 mm wide and 28-62 mm
deep against the committed drills' 29-40 and 36-48 mm, 0.38-2.1 kg against
0.70-1.38 kg). :func:`stretch_instance` scales one committed instance about
its canonical origin -- the base stays on z = 0, the functional direction
+y -- by ``(sx, sy, sz)``: mesh, annotated regions (centres and half
extents), and mass from the instance's own density (so the mass scales with
``sx * sy * sz``), written in the data set's layout (mesh, SDF,
annotations) as an imported object, usable by ``catgrasp benchmark --split
stress``, ``diagrams/handwritten_sweep.py --objects`` and the importer's
readers. :data:`STRESS_FAMILIES` are the stretches of the benchmark's
``stress`` split. Nothing here reads the test split or a real scan: a
stretched committed instance is still a tuned-on instance, stretched.

:func:`shrouded_instance` is a second kind of tuning copy: a committed spray
bottle rebuilt from its own generator parameters with a shroud behind the
neck (``head_back_drop`` of ``data.categories.build_spray_bottle``), the
head shape of the YCB Windex bottle that the generator never draws.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from catgrasp_drake.data.dataset import (
    WrittenInstance,
    imported_object,
    load_annotations,
    load_mesh,
    read_annotations,
    write_model_files,
    written_solid,
)
from catgrasp_drake.errors import InputError

#: The stress split's stretches (sx, sy, sz) of every committed instance, by family name: smaller and larger
#: as a whole (real drills 0.15-0.27 m tall), a thinner body (x: a drill handle 22 mm wide) and a deeper one
#: (y: a drill handle 62 mm deep).
STRESS_FAMILIES: dict[str, tuple[float, float, float]] = {
    "small": (0.8, 0.8, 0.8),
    "large": (1.2, 1.2, 1.2),
    "thin": (0.75, 1.0, 1.0),
    "deep": (1.0, 1.3, 1.0),
}
#: Stretch factors outside this range are refused: they no longer describe the category.
STRETCH_RANGE = (0.5, 2.0)


def check_stretch(stretch) -> np.ndarray:
    """``stretch`` as a (3,) array of factors in :data:`STRETCH_RANGE`; InputError naming the problem."""
    try:
        s = np.asarray(stretch, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InputError(f"stretch: expected three numbers (sx, sy, sz), got {stretch!r}") from None
    lo, hi = STRETCH_RANGE
    if s.shape != (3,) or not all(math.isfinite(v) and lo <= v <= hi for v in s):
        raise InputError(f"stretch: expected three factors in [{lo:g}, {hi:g}] (sx, sy, sz), got {stretch!r}")
    return s


def stretched_regions(regions: dict, stretch) -> dict:
    """Annotated regions (``{name: {"center", "half_extents"}}``, m, frame O) scaled by ``stretch``."""
    s = check_stretch(stretch)
    return {name: {"center": [round(float(c), 6) for c in np.asarray(r["center"], float) * s],
                   "half_extents": [round(float(h), 6) for h in np.asarray(r["half_extents"], float) * s]}
            for name, r in regions.items()}


def stretch_instance(category: str, instance: str, stretch, directory: str | Path,
                     name: str | None = None) -> WrittenInstance:
    """Write ``instance`` (committed, of ``category``) scaled by ``stretch`` (sx, sy, sz) about its canonical
    origin into ``directory`` as ``name`` (default ``<instance>_<sx>x<sy>x<sz>``); see the module docstring.

    The annotations keep the source: ``stretched_from`` and ``stretch``."""
    s = check_stretch(stretch)
    annotations = load_annotations(category, instance)
    mesh = load_mesh(category, instance).copy()
    mesh.apply_transform(np.diag([*s, 1.0]))
    name = name or f"{instance}_" + "x".join(f"{v:g}" for v in s)
    solid = written_solid(mesh, annotations["density_kg_m3"])
    return write_model_files(Path(directory), name, category, mesh, solid, float(solid.mass),
                             stretched_regions(annotations["regions"], s),
                             {"density_kg_m3": solid.density, "stretched_from": instance,
                              "stretch": [float(v) for v in s]})


#: A shrouded copy's head reaches down behind the neck to this height above its trigger region's centre (m): the
#: YCB Windex bottle's 5.4 mm (``benchmarks/results/experiments/s41_windex_thumb``).
SHROUD_ABOVE_TRIGGER_M = 0.005


def shrouded_instance(source: str | Path, directory: str | Path, name: str | None = None,
                      above_trigger_m: float = SHROUD_ABOVE_TRIGGER_M) -> WrittenInstance:
    """Write the spray bottle ``source`` rebuilt from its own generator parameters with a shroud: the head's
    back hangs down behind the neck to ``above_trigger_m`` (m) above the trigger region's centre. ``source`` is a
    committed instance's name or a generated bottle's object directory (a ``val`` or ``test`` split bottle,
    written by the generator, so its annotations hold its parameters). Trigger region, body and fill are the
    bottle's own. Written into ``directory`` as ``name`` (default ``<instance>_shroud``) like
    :func:`stretch_instance`; the annotations keep ``shrouded_from``."""
    from catgrasp_drake.data.categories import REGION_MARGIN_M, build_spray_bottle

    if not (math.isfinite(above_trigger_m) and 0.0 <= above_trigger_m <= 0.03):
        raise InputError(f"above_trigger_m: expected 0-0.03 m above the trigger's centre, got {above_trigger_m!r}")
    if isinstance(source, Path) or Path(source).is_dir():
        category, instance = imported_object(source)
        if category != "spray_bottle":
            raise InputError(f"{source}: a shroud is drawn on spray bottles, not on a {category}")
        annotations = read_annotations(Path(source) / "annotations.json")
        if "head_height" not in annotations.get("params", {}):
            raise InputError(f"{source}: not a generated bottle (its annotations hold no generator parameters)")
    else:
        instance, annotations = str(source), load_annotations("spray_bottle", str(source))
    params = dict(annotations["params"])
    trigger = annotations["regions"]["trigger"]
    # the region's top (without its margin) is the head's underside, where the shroud starts
    drop = trigger["half_extents"][2] - REGION_MARGIN_M["trigger"] - above_trigger_m
    if drop <= 0.0:
        raise InputError(f"{instance}: its trigger is too short for a shroud {above_trigger_m} m above its centre")
    generated = build_spray_bottle(params | {"head_back_drop": round(drop, 5)})
    solid = written_solid(generated.mesh, annotations["density_kg_m3"])
    return write_model_files(Path(directory), name or f"{instance}_shroud", "spray_bottle", generated.mesh, solid,
                             float(solid.mass), generated.regions,
                             {"density_kg_m3": solid.density, "params": generated.params, "shrouded_from": instance})
