"""Generate the project's UR10 arm model (``models/ur10/ur10.urdf``) from the standard DH parameters.

Run as::

    python -m tools.ur10_model --out models/ur10

Kinematics: Universal Robots' published standard DH parameters of the UR10
(d1 = 0.1273, a2 = -0.612, a3 = -0.5723, d4 = 0.163941, d5 = 0.1157,
d6 = 0.0922; alpha = pi/2, 0, 0, pi/2, -pi/2, 0), so that the pose of the
flange ``ur10_tool0`` in ``ur10_base_link`` is exactly
``prod_i Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i)`` (:func:`dh_forward_kinematics`).
Each link ``i``'s frame is DH frame ``i-1`` turned by ``q_i`` about its z axis
(the joint axis); the constant part ``Tz(d) Tx(a) Rx(alpha)`` of the previous
DH row is the joint origin.

Geometry: cylinders and capsules around the joint housings and tubes (sizes
estimated from the UR10 data sheet drawing: base/shoulder housings 150 mm,
elbow 126 mm, wrists 92 mm diameter). Collision geometry is rigid
(point contact), not compliant. Masses are UR's published link masses
(shoulder 7.1, upper arm 12.7, forearm 4.27, wrists 2.0, 2.0, 0.365 kg);
centres of mass and inertias follow from the primitives at uniform density.
Collisions between adjacent links are filtered (Drake does this for bodies
connected by a joint), and within the base group and within the wrist group.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from catgrasp_drake.core.fileio import atomic_write_bytes
from catgrasp_drake.robot.specs import UR10_ACTUATOR_GAINS, UR10_JOINT_NAMES, UR10_LINK_NAMES
from tools.urdf_util import combine_inertias, fmt, origin_xml, rotation_z_to, vec

#: Standard DH parameters of the UR10: (d, a, alpha) per joint.
DH_PARAMETERS: tuple[tuple[float, float, float], ...] = (
    (0.1273, 0.0, math.pi / 2),
    (0.0, -0.612, 0.0),
    (0.0, -0.5723, 0.0),
    (0.163941, 0.0, math.pi / 2),
    (0.1157, 0.0, -math.pi / 2),
    (0.0922, 0.0, 0.0),
)

LINK_NAMES = UR10_LINK_NAMES
JOINT_NAMES = UR10_JOINT_NAMES
TOOL_FRAME = "ur10_tool0"

#: Published UR10 link masses [kg] (base link: welded, any value).
LINK_MASSES: tuple[float, ...] = (4.0, 7.1, 12.7, 4.27, 2.0, 2.0, 0.365)
JOINT_LIMITS: tuple[tuple[float, float], ...] = (
    (-2 * math.pi, 2 * math.pi),
    (-2 * math.pi, 2 * math.pi),
    (-math.pi, math.pi),
    (-2 * math.pi, 2 * math.pi),
    (-2 * math.pi, 2 * math.pi),
    (-2 * math.pi, 2 * math.pi),
)
#: UR10 data sheet: 120 deg/s base and shoulder, 180 deg/s elbow and wrists.
VELOCITY_LIMITS: tuple[float, ...] = (2.094, 2.094, 3.142, 3.142, 3.142, 3.142)
#: (Kp, Kd, effort limit) per joint: the runtime's table (catgrasp_drake.robot.specs).
ACTUATOR_GAINS = UR10_ACTUATOR_GAINS
FRICTION = (0.8, 0.6)  # static, dynamic

# Primitives per link, in the link frame (z = the link's joint axis):
# ("cylinder" | "capsule", p_start, p_end, radius): the axis runs from p_start to p_end.
_D1, _A2, _A3, _D4, _D5, _D6 = 0.1273, -0.612, -0.5723, 0.163941, 0.1157, 0.0922
_UPPER_OFFSET = 0.176  # upper-arm tube offset along the shoulder axis
_FORE_OFFSET = 0.05  # forearm tube offset along the elbow axis
PRIMITIVES: dict[str, list[tuple[str, tuple, tuple, float]]] = {
    "ur10_base_link": [("cylinder", (0, 0, 0.0), (0, 0, 0.086), 0.075)],
    "ur10_shoulder_link": [
        ("cylinder", (0, 0, 0.086), (0, 0, _D1), 0.075),
        ("cylinder", (0, 0.075, _D1), (0, -0.075, _D1), 0.075),
    ],
    "ur10_upper_arm_link": [
        ("cylinder", (0, 0, 0.075), (0, 0, 0.25), 0.075),
        ("capsule", (-0.06, 0, _UPPER_OFFSET), (_A2 + 0.06, 0, _UPPER_OFFSET), 0.054),
        ("cylinder", (_A2, 0, 0.07), (_A2, 0, 0.24), 0.063),
    ],
    "ur10_forearm_link": [
        ("cylinder", (0, 0, -0.0), (0, 0, 0.07), 0.058),
        ("capsule", (-0.05, 0, _FORE_OFFSET), (_A3 + 0.05, 0, _FORE_OFFSET), 0.042),
        ("cylinder", (_A3, 0, 0.0), (_A3, 0, 0.095), 0.046),
    ],
    "ur10_wrist_1_link": [("cylinder", (0, 0, 0.095), (0, 0, _D4 + 0.046), 0.046)],
    "ur10_wrist_2_link": [("cylinder", (0, 0, -0.046), (0, 0, _D5 - 0.03), 0.046)],
    "ur10_wrist_3_link": [("cylinder", (0, 0, -0.03), (0, 0, _D6), 0.045)],
}
_COLORS = {
    "ur10_base_link": (0.25, 0.27, 0.32, 1.0),
    "ur10_shoulder_link": (0.3, 0.5, 0.75, 1.0),
    "ur10_upper_arm_link": (0.82, 0.84, 0.87, 1.0),
    "ur10_forearm_link": (0.82, 0.84, 0.87, 1.0),
    "ur10_wrist_1_link": (0.3, 0.5, 0.75, 1.0),
    "ur10_wrist_2_link": (0.82, 0.84, 0.87, 1.0),
    "ur10_wrist_3_link": (0.3, 0.5, 0.75, 1.0),
}


def dh_transform(q: float, d: float, a: float, alpha: float) -> np.ndarray:
    """4x4 standard DH transform Rz(q) Tz(d) Tx(a) Rx(alpha)."""
    cq, sq, ca, sa = math.cos(q), math.sin(q), math.cos(alpha), math.sin(alpha)
    return np.array(
        [
            [cq, -sq * ca, sq * sa, a * cq],
            [sq, cq * ca, -cq * sa, a * sq],
            [0.0, sa, ca, d],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def dh_forward_kinematics(q) -> np.ndarray:
    """4x4 pose of ``ur10_tool0`` in ``ur10_base_link`` by the DH formula."""
    q = np.asarray(q, float)
    if q.shape != (6,):
        raise ValueError(f"expected 6 joint angles, got shape {q.shape}")
    X = np.eye(4)
    for qi, (d, a, alpha) in zip(q, DH_PARAMETERS):
        X = X @ dh_transform(qi, d, a, alpha)
    return X


def _primitive_geometry(kind: str, p0, p1, r: float):
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    axis = p1 - p0
    length = float(np.linalg.norm(axis))
    X = np.eye(4)
    X[:3, :3] = rotation_z_to(axis)
    X[:3, 3] = 0.5 * (p0 + p1)
    if kind == "cylinder":
        return f'<cylinder radius="{fmt(r)}" length="{fmt(length)}"/>', X, length
    return f'<capsule radius="{fmt(r)}" length="{fmt(length)}"/>', X, length


def _inertia(kind: str, r: float, length: float, X: np.ndarray, density: float):
    R = X[:3, :3]
    if kind == "cylinder":
        m = density * math.pi * r * r * length
        i_axis, i_perp = m * r * r / 2, m * (3 * r * r + length * length) / 12
    else:
        mc = density * math.pi * r * r * length
        mh = density * 2 / 3 * math.pi * r**3
        m = mc + 2 * mh
        i_axis = mc * r * r / 2 + 2 * mh * 2 * r * r / 5
        i_perp = (mc * (r * r / 4 + length * length / 12)
                  + 2 * mh * (2 * r * r / 5 + length * length / 4 + 3 * length * r / 8))
    return m, X[:3, 3], R @ np.diag([i_perp, i_perp, i_axis]) @ R.T


def build_urdf() -> str:
    out = [
        '<?xml version="1.0"?>',
        "<!-- Generated by tools/ur10_model.py; do not edit. -->",
        "<!-- UR10 from the standard DH parameters; ur10_base_link = DH frame 0 (z up); ur10_tool0 = DH frame 6. -->",
        '<robot name="ur10" xmlns:drake="http://drake.mit.edu">',
    ]
    for name, mass in zip(LINK_NAMES, LINK_MASSES):
        geoms = [(kind,) + _primitive_geometry(kind, p0, p1, r) + (r,) for kind, p0, p1, r in PRIMITIVES[name]]
        unit = [_inertia(kind, r, length, X, 1.0) for kind, _, X, length, r in geoms]
        volume = sum(u[0] for u in unit)
        m, com, inertia = combine_inertias([(u[0] * mass / volume, u[1], u[2] * mass / volume) for u in unit])
        out.append(f'  <link name="{name}">')
        out.append("    <inertial>")
        out.append(f'      <origin xyz="{vec(com)}" rpy="0 0 0"/>')
        out.append(f'      <mass value="{fmt(m)}"/>')
        out.append(
            f'      <inertia ixx="{fmt(inertia[0, 0])}" ixy="{fmt(inertia[0, 1])}" ixz="{fmt(inertia[0, 2])}"'
            f' iyy="{fmt(inertia[1, 1])}" iyz="{fmt(inertia[1, 2])}" izz="{fmt(inertia[2, 2])}"/>'
        )
        out.append("    </inertial>")
        for k, (_, geom, X, _, _) in enumerate(geoms):
            out.append(f'    <visual name="{name}_visual_{k}">')
            out.append(f"      {origin_xml(X)}")
            out.append(f"      <geometry>{geom}</geometry>")
            out.append(f'      <material name="{name}_color"><color rgba="{vec(_COLORS[name])}"/></material>')
            out.append("    </visual>")
        for k, (_, geom, X, _, _) in enumerate(geoms):
            out.append(f'    <collision name="{name}_collision_{k}">')
            out.append(f"      {origin_xml(X)}")
            out.append(f"      <geometry>{geom}</geometry>")
            out.append("      <drake:proximity_properties>")
            out.append(f'        <drake:mu_static value="{fmt(FRICTION[0])}"/>')
            out.append(f'        <drake:mu_dynamic value="{fmt(FRICTION[1])}"/>')
            out.append("      </drake:proximity_properties>")
            out.append("    </collision>")
        out.append("  </link>")
    out.append(f'  <link name="{TOOL_FRAME}"/>')
    for i, joint in enumerate(JOINT_NAMES):
        X = np.eye(4) if i == 0 else dh_transform(0.0, *DH_PARAMETERS[i - 1])
        lo, hi = JOINT_LIMITS[i]
        out.append(f'  <joint name="{joint}" type="revolute">')
        out.append(f'    <parent link="{LINK_NAMES[i]}"/>')
        out.append(f'    <child link="{LINK_NAMES[i + 1]}"/>')
        out.append(f"    {origin_xml(X)}")
        out.append('    <axis xyz="0 0 1"/>')
        out.append(
            f'    <limit lower="{fmt(lo)}" upper="{fmt(hi)}" velocity="{fmt(VELOCITY_LIMITS[i])}"'
            f' effort="{fmt(ACTUATOR_GAINS[joint][2])}"/>'
        )
        out.append('    <dynamics damping="0.0"/>')
        out.append("  </joint>")
    out.append('  <joint name="ur10_flange_joint" type="fixed">')
    out.append(f'    <parent link="{LINK_NAMES[-1]}"/>')
    out.append(f'    <child link="{TOOL_FRAME}"/>')
    out.append(f"    {origin_xml(dh_transform(0.0, *DH_PARAMETERS[-1]))}")
    out.append("  </joint>")
    for joint in JOINT_NAMES:
        p, d, _ = ACTUATOR_GAINS[joint]
        out.append(f'  <transmission name="{joint}_transmission">')
        out.append("    <type>transmission_interface/SimpleTransmission</type>")
        out.append(f'    <joint name="{joint}"><hardwareInterface>EffortJointInterface</hardwareInterface></joint>')
        out.append(f'    <actuator name="{joint}_actuator">')
        out.append(f'      <drake:controller_gains p="{fmt(p)}" d="{fmt(d)}"/>')
        out.append("    </actuator>")
        out.append("  </transmission>")
    groups = {"ur10_base_group": LINK_NAMES[:3], "ur10_wrist_group": LINK_NAMES[4:] + (TOOL_FRAME,)}
    for group, members in groups.items():
        out.append(f'  <drake:collision_filter_group name="{group}">')
        for m in members:
            out.append(f'    <drake:member link="{m}"/>')
        out.append(f'    <drake:ignored_collision_filter_group name="{group}"/>')
        out.append("  </drake:collision_filter_group>")
    out.append("</robot>")
    return "\n".join(out) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="output folder (ur10.urdf is written there)")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_bytes(out / "ur10.urdf", build_urdf().encode())
    sys.stdout.write(f"wrote {out / 'ur10.urdf'}\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
