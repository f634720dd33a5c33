"""Offline tools, outside the runtime package: they (re)generate files the runtime reads.

Run from the repository root (``python -m tools.<name> ...``):

- ``tools.svh_model``: ``models/svh/svh_right.urdf`` from the vendor's SVH description;
- ``tools.ur10_model``: ``models/ur10/ur10.urdf`` from the UR10's DH parameters;
- ``tools.render_hand``: pictures of the hand and the arm (``docs/hand.png``, ``docs/arm_hand.png``);
- ``tools.fitting``, ``tools.urdf_util``: primitive fitting and URDF writing for the generators.

Nothing in ``catgrasp_drake`` imports them; trial caches do not depend on them.
"""
