"""The numerical core imports with only numpy and scipy (pydrake, open3d, trimesh made unimportable)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]

CORE_MODULES = [
    "catgrasp_drake.core",
    "catgrasp_drake.core.cpd",
    "catgrasp_drake.core.em",
    "catgrasp_drake.core.deformation",
    "catgrasp_drake.core.rotations",
    "catgrasp_drake.core.shape_space",
    "catgrasp_drake.core.inference",
    "catgrasp_drake.core.threads",
    "catgrasp_drake.core.visibility",
    "catgrasp_drake.core.fileio",
    "catgrasp_drake.core.validation",
]

SCRIPT = f"""
import sys
for name in ("pydrake", "open3d", "trimesh", "matplotlib", "pycpd", "probreg"):
    sys.modules[name] = None  # any import of these now raises ImportError
import importlib, numpy as np
for m in {CORE_MODULES!r}:
    importlib.import_module(m)
from catgrasp_drake.core.cpd import nonrigid_cpd
rng0, rng1 = np.random.default_rng(0), np.random.default_rng(1)
r = nonrigid_cpd(rng0.normal(size=(20, 3)) * 0.05, rng1.normal(size=(20, 3)) * 0.05, max_iter=3)
allowed = ("numpy", "scipy", "catgrasp_drake")
third = sorted({{k.split(".")[0] for k, v in sys.modules.items() if v is not None}})
print(",".join(third))
"""


def test_core_imports_with_numpy_and_scipy_only():
    out = subprocess.run([sys.executable, "-c", SCRIPT], cwd=REPO, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    loaded = set(out.stdout.strip().split(","))
    assert not loaded & {"pydrake", "open3d", "trimesh", "matplotlib", "pycpd", "probreg", "sklearn", "threadpoolctl"}
