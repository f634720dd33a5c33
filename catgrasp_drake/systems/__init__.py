"""Drake LeafSystems: thin wrappers over the package's pure functions.

Import the submodules explicitly (they import pydrake):
``from catgrasp_drake.systems.object_cloud import ObjectCloudSystem``.
"""
