"""Grasping motions: descriptors, sampling, functional constraints, success metrics.

Kept import-light: submodules are imported explicitly
(``from catgrasp_drake.grasping.motion import GraspMotion``).
"""
