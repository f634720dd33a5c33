"""catgrasp_drake: category-based functional grasp transfer on Drake.

Implements Rodriguez & Behnke, "Transferring Category-based Functional Grasping
Skills by Latent Space Non-Rigid Registration" (RA-L 2018).

This top-level module stays import-light on purpose: ``catgrasp_drake.core``
must import with only numpy and scipy available.
"""

from catgrasp_drake.errors import CatgraspError, InputError, ModelFileError

__version__ = "0.1.0"
__all__ = ["CatgraspError", "InputError", "ModelFileError", "__version__"]
