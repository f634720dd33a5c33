"""Generate the project's Schunk SVH-like right hand model (``models/svh/svh_right.urdf``).

Run as::

    python -m tools.svh_model --reference ../shared/reference/schunk_svh --out models/svh

What comes from where:

- Kinematics (joint origins, axes, position limits, velocity limits, mimic
  multipliers and offsets) are read from the vendor's URDF
  (``svh_right.urdf`` of the FZI ``schunk_svh_driver`` description, LGPL). The
  vendor's fixed joints are collapsed: every link hanging on a chain of fixed
  joints is merged into the nearest link with a moving (or no) parent joint and
  its meshes and child-joint origins are re-expressed in that link's frame by
  composing the fixed transforms, so all frames stay exact. The hand base link
  frame is the vendor's ``base_link`` frame.
- Collision geometry: one primitive per vendor mesh, fitted to the mesh
  vertices by :mod:`tools.fitting` (capsules for finger, thumb
  and knuckle links; the palm housings get bounding boxes in the link frame; the
  round wrist piece a cylinder about the wrist axis). All hand geometry is
  compliant hydroelastic.
- Visual geometry: the same primitives, coloured.
- Inertia: from the primitives. Finger/thumb links at ``FINGER_DENSITY``; the
  two palm bodies share the rest of ``HAND_TOTAL_MASS`` (the SVH carries its
  nine motors in the palm) in proportion to their primitive volumes.
- Actuators: one ``<transmission>`` per actuated joint with Drake PD gains
  (``drake:controller_gains``, see Drake's parsing documentation
  "drake:controller_gains": URDF path ``/robot/joint/actuator/drake:controller_gains``)
  and the joint's effort limit, which Drake's SAP solver uses to clamp the PD
  torque: the fingers close compliantly, like the current-limited real hand.

The vendor files are only read; nothing of them is copied into the output
besides the numbers listed above.
"""

from __future__ import annotations

import argparse
import math
import sys
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from catgrasp_drake.core.fileio import atomic_write_bytes
from catgrasp_drake.errors import InputError, ModelFileError
from catgrasp_drake.robot.specs import SVH_ACTUATED_JOINTS, SVH_ACTUATOR_GAINS, SVH_JOINT_NAMES, SVH_LINK_NAMES
from tools import fitting
from tools.urdf_util import combine_inertias, fmt, origin_xml, rotation_z_to, rpy_to_matrix, vec

#: Vendor link -> project link name, vendor joint -> project joint name (actuated first), PD gains:
#: the runtime's tables (catgrasp_drake.robot.specs), written into the URDF here.
LINK_NAMES = SVH_LINK_NAMES
JOINT_NAMES = SVH_JOINT_NAMES
ACTUATED_JOINTS = SVH_ACTUATED_JOINTS
ACTUATOR_GAINS = SVH_ACTUATOR_GAINS

#: Effort limit written on the (unactuated) mimic joints; unused by Drake for joints without actuator.
MIMIC_EFFORT = 10.0
#: Viscous joint damping [N m s/rad] on every hand joint (keeps free fingers from ringing).
JOINT_DAMPING = 0.002

HAND_TOTAL_MASS = 1.3  # kg (Schunk SVH data sheet: ~1.3 kg)
FINGER_DENSITY = 700.0  # kg/m^3 over the fitted capsule volumes (hollow shells + cables)

# Contact properties of every hand collision geometry.
HYDROELASTIC_MODULUS = 5.0e6  # Pa
HUNT_CROSSLEY_DISSIPATION = 5.0  # s/m (used by the TAMSI/similar/lagged approximations)
RELAXATION_TIME = 0.02  # s (used by SAP instead of Hunt-Crossley)
MU_STATIC = 1.0
MU_DYNAMIC = 1.0
MESH_RESOLUTION_HINT = 0.006  # m, tessellation of compliant capsules/cylinders (0.004: same grasps, 0.6x the speed)
HYDROELASTIC_MARGIN = 1.0e-4  # m, Drake's recommended value

#: Which primitive each vendor mesh gets (default capsule).
_PRIMITIVE_OF_VENDOR_LINK = {
    "right_hand_base_link": "cylinder_z",  # round wrist piece
    "right_hand_e1": "boxes",  # palm housing: boxes stacked along the finger axis
    "right_hand_e2": "boxes",  # moving palm part carrying ring and little finger
}

_PALM_BODIES = ("svh_base_link", "svh_palm_flex_link")

_COLORS = {
    "palm": (0.22, 0.23, 0.26, 1.0),
    "wrist": (0.62, 0.64, 0.68, 1.0),
    "knuckle": (0.12, 0.12, 0.13, 1.0),
    "phalanx": (0.80, 0.81, 0.84, 1.0),
    "distal": (0.93, 0.93, 0.95, 1.0),
    "index_distal": (0.95, 0.45, 0.12, 1.0),
}


# --------------------------------------------------------------------------- reading


@dataclass
class VendorJoint:
    name: str
    type: str
    parent: str
    child: str
    X_PJ: np.ndarray  # 4x4
    axis: np.ndarray
    lower: float = 0.0
    upper: float = 0.0
    velocity: float = 0.0
    mimic: tuple[str, float, float] | None = None  # (leader, multiplier, offset)


@dataclass
class VendorModel:
    links: dict[str, list[tuple[Path, np.ndarray]]]  # link -> [(mesh path, X_LinkMesh 4x4)]
    joints: dict[str, VendorJoint]


def make_transform(xyz=(0, 0, 0), rpy=(0, 0, 0)) -> np.ndarray:
    X = np.eye(4)
    X[:3, :3] = rpy_to_matrix(rpy)
    X[:3, 3] = np.asarray(xyz, float)
    return X


def _floats(text: str | None, n: int, default: float = 0.0) -> list[float]:
    if text is None:
        return [default] * n
    vals = [float(v) for v in text.split()]
    if len(vals) != n:
        raise ModelFileError(f"expected {n} numbers, got {text!r}")
    return vals


def _origin(elem) -> np.ndarray:
    o = elem.find("origin")
    if o is None:
        return np.eye(4)
    return make_transform(_floats(o.get("xyz"), 3), _floats(o.get("rpy"), 3))


def read_vendor_urdf(reference_dir: str | Path) -> VendorModel:
    """Read links (collision meshes) and joints of the vendor's ``svh_right.urdf``."""
    ref = Path(reference_dir)
    path = ref / "svh_right.urdf"
    if not path.is_file():
        raise ModelFileError(f"{path}: not found (pass --reference pointing at the schunk_svh reference folder)")
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as exc:
        raise ModelFileError(f"{path}: not valid XML ({exc})") from exc
    links: dict[str, list[tuple[Path, np.ndarray]]] = {}
    for link in root.findall("link"):
        meshes = []
        for col in link.findall("collision"):
            mesh = col.find("geometry/mesh")
            if mesh is None:
                continue
            mesh_path = ref / mesh.get("filename")
            if not mesh_path.is_file():
                raise ModelFileError(f"{mesh_path}: mesh referenced by {path.name} not found")
            scale = _floats(mesh.get("scale"), 3, 1.0)
            if not np.allclose(scale, 1.0):
                raise ModelFileError(f"{path}: scaled meshes are not supported ({mesh_path.name})")
            meshes.append((mesh_path, _origin(col)))
        links[link.get("name")] = meshes
    joints: dict[str, VendorJoint] = {}
    for j in root.findall("joint"):
        lim = j.find("limit")
        mim = j.find("mimic")
        axis = j.find("axis")
        joints[j.get("name")] = VendorJoint(
            name=j.get("name"),
            type=j.get("type"),
            parent=j.find("parent").get("link"),
            child=j.find("child").get("link"),
            X_PJ=_origin(j),
            axis=np.array(_floats(axis.get("xyz") if axis is not None else "1 0 0", 3)),
            lower=float(lim.get("lower", 0.0)) if lim is not None else 0.0,
            upper=float(lim.get("upper", 0.0)) if lim is not None else 0.0,
            velocity=float(lim.get("velocity", 0.0)) if lim is not None else 0.0,
            mimic=(mim.get("joint"), float(mim.get("multiplier", 1.0)), float(mim.get("offset", 0.0)))
            if mim is not None
            else None,
        )
    return VendorModel(links=links, joints=joints)


# --------------------------------------------------------------------------- collapsing


@dataclass
class Body:
    name: str
    meshes: list[tuple[str, Path, np.ndarray]] = field(default_factory=list)  # (vendor link, path, X_BodyMesh)
    primitives: list[tuple[str, object, str]] = field(default_factory=list)  # (kind, fit, colour key)
    mass: float = 0.0
    com: np.ndarray = field(default_factory=lambda: np.zeros(3))
    inertia: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))  # about com, body axes


@dataclass
class Joint:
    name: str
    parent: str
    child: str
    X_PJ: np.ndarray
    axis: np.ndarray
    lower: float
    upper: float
    velocity: float
    mimic: tuple[str, float, float] | None


def collapse_fixed_joints(vendor: VendorModel) -> tuple[dict[str, Body], list[Joint]]:
    """Merge fixed-joint chains: returns project bodies and the moving joints between them."""
    parent_joint = {j.child: j for j in vendor.joints.values()}
    roots = [name for name in vendor.links if name not in parent_joint]
    if len(roots) != 1:
        raise ModelFileError(f"vendor URDF must have exactly one root link, found {roots}")

    def body_root(link: str) -> tuple[str, np.ndarray]:
        """(body root link, X_RootLink) following fixed joints upwards."""
        X = np.eye(4)
        while link in parent_joint and parent_joint[link].type == "fixed":
            j = parent_joint[link]
            X = j.X_PJ @ X
            link = j.parent
        return link, X

    bodies: dict[str, Body] = {}
    for link, meshes in vendor.links.items():
        root, X_RL = body_root(link)
        if root not in LINK_NAMES:
            raise ModelFileError(f"vendor link {root!r} has no project name (update LINK_NAMES)")
        body = bodies.setdefault(root, Body(name=LINK_NAMES[root]))
        for mesh_path, X_LM in meshes:
            body.meshes.append((link, mesh_path, X_RL @ X_LM))
    joints = []
    for j in vendor.joints.values():
        if j.type == "fixed":
            continue
        if j.type != "revolute":
            raise ModelFileError(f"vendor joint {j.name!r} has unsupported type {j.type!r}")
        if j.name not in JOINT_NAMES:
            raise ModelFileError(f"vendor joint {j.name!r} has no project name (update JOINT_NAMES)")
        parent_root, X_RP = body_root(j.parent)
        if j.child not in LINK_NAMES:
            raise ModelFileError(f"vendor joint {j.name!r} moves link {j.child!r} that has no project name")
        mimic = None
        if j.mimic is not None:
            mimic = (JOINT_NAMES[j.mimic[0]], j.mimic[1], j.mimic[2])
        joints.append(
            Joint(
                name=JOINT_NAMES[j.name],
                parent=LINK_NAMES[parent_root],
                child=LINK_NAMES[j.child],
                X_PJ=X_RP @ j.X_PJ,
                axis=j.axis / np.linalg.norm(j.axis),
                lower=j.lower,
                upper=j.upper,
                velocity=j.velocity,
                mimic=mimic,
            )
        )
    order = {name: k for k, name in enumerate(JOINT_NAMES.values())}
    joints.sort(key=lambda jt: order[jt.name])
    by_name = {b.name: b for b in bodies.values()}
    return by_name, joints


# --------------------------------------------------------------------------- fitting, inertia


def _load_vertices(path: Path) -> np.ndarray:
    import trimesh

    mesh = trimesh.load(str(path), force="mesh", process=False)
    v = np.asarray(mesh.vertices, float)
    if len(v) < 4:
        raise ModelFileError(f"{path}: mesh has too few vertices")
    return v


def _colour_key(body: str, kind: str) -> str:
    if body in _PALM_BODIES:
        return "wrist" if kind == "cylinder_z" else "palm"
    if body == "svh_index_distal_link":
        return "index_distal"
    if "knuckle" in body or body == "svh_thumb_base_link":
        return "knuckle"
    if "distal" in body:
        return "distal"
    return "phalanx"


def fit_primitives(bodies: dict[str, Body]) -> None:
    """Fit one primitive to each mesh of each body (in the body frame)."""
    for body in bodies.values():
        for vendor_link, path, X_BM in body.meshes:
            v = _load_vertices(path)
            p_B = v @ X_BM[:3, :3].T + X_BM[:3, 3]
            kind = _PRIMITIVE_OF_VENDOR_LINK.get(vendor_link, "capsule")
            if kind == "capsule":
                fit = fitting.fit_capsule(p_B)
            elif kind == "boxes":
                for box in fitting.fit_boxes_along_axis(p_B, axis=2):
                    body.primitives.append(("box", box, _colour_key(body.name, "box")))
                continue
            elif kind == "cylinder_z":
                fit = fitting.fit_cylinder(p_B, np.array([0.0, 0.0, 1.0]))
            else:  # pragma: no cover - table above is closed
                raise AssertionError(kind)
            body.primitives.append((kind, fit, _colour_key(body.name, kind)))


def _primitive_inertia(kind: str, fit, density: float) -> tuple[float, np.ndarray, np.ndarray]:
    """(mass, centre, inertia about centre in body axes) of a uniform-density primitive."""
    if kind == "capsule":
        r, L = fit.radius, fit.length
        mc = density * math.pi * r * r * L
        mh = density * 2.0 / 3.0 * math.pi * r**3
        i_axis = mc * r * r / 2.0 + 2.0 * mh * 2.0 * r * r / 5.0
        i_perp = mc * (r * r / 4.0 + L * L / 12.0) + 2.0 * mh * (2.0 * r * r / 5.0 + L * L / 4.0 + 3.0 * L * r / 8.0)
        m = mc + 2.0 * mh
        R = rotation_z_to(fit.axis_B)
        I_local = np.diag([i_perp, i_perp, i_axis])
        return m, fit.p_BC, R @ I_local @ R.T
    if kind == "cylinder_z":
        r, L = fit.radius, fit.length
        m = density * math.pi * r * r * L
        i_axis = m * r * r / 2.0
        i_perp = m * (3.0 * r * r + L * L) / 12.0
        R = rotation_z_to(fit.axis_B)
        return m, fit.p_BC, R @ np.diag([i_perp, i_perp, i_axis]) @ R.T
    if kind == "box":
        a, b, c = fit.size
        m = density * a * b * c
        I_local = m / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
        return m, fit.p_BC, fit.R_BC @ I_local @ fit.R_BC.T
    raise AssertionError(kind)  # pragma: no cover


def assign_inertia(bodies: dict[str, Body]) -> None:
    """Finger links at FINGER_DENSITY; the palm bodies share the rest of HAND_TOTAL_MASS."""
    finger_mass = 0.0
    for body in bodies.values():
        if body.name in _PALM_BODIES:
            continue
        parts = [_primitive_inertia(k, f, FINGER_DENSITY) for k, f, _ in body.primitives]
        body.mass, body.com, body.inertia = combine_inertias(parts)
        finger_mass += body.mass
    palm_volume = sum(f.volume for name in _PALM_BODIES for _, f, _ in bodies[name].primitives)
    palm_density = (HAND_TOTAL_MASS - finger_mass) / palm_volume
    if palm_density <= 0:
        raise InputError("finger links alone exceed HAND_TOTAL_MASS; lower FINGER_DENSITY")
    for name in _PALM_BODIES:
        body = bodies[name]
        parts = [_primitive_inertia(k, f, palm_density) for k, f, _ in body.primitives]
        body.mass, body.com, body.inertia = combine_inertias(parts)


# --------------------------------------------------------------------------- writing


def _geometry_xml(kind: str, fit) -> tuple[str, np.ndarray]:
    """(<geometry> inner XML, X_BG 4x4)."""
    X = np.eye(4)
    X[:3, 3] = fit.p_BC
    if kind == "capsule":
        X[:3, :3] = rotation_z_to(fit.axis_B)
        return f'<capsule radius="{fmt(fit.radius)}" length="{fmt(fit.length)}"/>', X
    if kind == "cylinder_z":
        X[:3, :3] = rotation_z_to(fit.axis_B)
        return f'<cylinder radius="{fmt(fit.radius)}" length="{fmt(fit.length)}"/>', X
    if kind == "box":
        X[:3, :3] = fit.R_BC
        return f'<box size="{vec(fit.size)}"/>', X
    raise AssertionError(kind)  # pragma: no cover


def _proximity_xml(kind: str) -> str:
    hint = f'\n          <drake:mesh_resolution_hint value="{fmt(MESH_RESOLUTION_HINT)}"/>' if kind != "box" else ""
    return f"""<drake:proximity_properties>
          <drake:compliant_hydroelastic/>
          <drake:hydroelastic_modulus value="{fmt(HYDROELASTIC_MODULUS)}"/>{hint}
          <drake:hunt_crossley_dissipation value="{fmt(HUNT_CROSSLEY_DISSIPATION)}"/>
          <drake:relaxation_time value="{fmt(RELAXATION_TIME)}"/>
          <drake:hydroelastic_margin value="{fmt(HYDROELASTIC_MARGIN)}"/>
          <drake:mu_static value="{fmt(MU_STATIC)}"/>
          <drake:mu_dynamic value="{fmt(MU_DYNAMIC)}"/>
        </drake:proximity_properties>"""


def build_urdf(bodies: dict[str, Body], joints: list[Joint], source_note: str) -> str:
    out = [
        '<?xml version="1.0"?>',
        "<!-- Generated by tools/svh_model.py; do not edit. -->",
        f"<!-- {source_note} -->",
        "<!-- Frames: svh_base_link = wrist axis origin, +z along the fingers, +y out of the palm"
        " (approach), +x from the index toward the little finger; thumb on the -x side. -->",
        '<robot name="svh_right" xmlns:drake="http://drake.mit.edu">',
    ]
    for key, rgba in _COLORS.items():
        out.append(f'  <material name="svh_{key}"><color rgba="{vec(rgba)}"/></material>')
    ordered = ["svh_base_link"] + [b for b in LINK_NAMES.values() if b != "svh_base_link"]
    for name in ordered:
        b = bodies[name]
        out.append(f'  <link name="{name}">')
        out.append("    <inertial>")
        out.append(f'      <origin xyz="{vec(b.com)}" rpy="0 0 0"/>')
        out.append(f'      <mass value="{fmt(b.mass)}"/>')
        I = b.inertia
        out.append(
            f'      <inertia ixx="{fmt(I[0, 0])}" ixy="{fmt(I[0, 1])}" ixz="{fmt(I[0, 2])}"'
            f' iyy="{fmt(I[1, 1])}" iyz="{fmt(I[1, 2])}" izz="{fmt(I[2, 2])}"/>'
        )
        out.append("    </inertial>")
        for k, (kind, fit, colour) in enumerate(b.primitives):
            geom, X = _geometry_xml(kind, fit)
            out.append(f'    <visual name="{name}_visual_{k}">')
            out.append(f"      {origin_xml(X)}")
            out.append(f"      <geometry>{geom}</geometry>")
            out.append(f'      <material name="svh_{colour}"/>')
            out.append("    </visual>")
        for k, (kind, fit, _) in enumerate(b.primitives):
            geom, X = _geometry_xml(kind, fit)
            out.append(f'    <collision name="{name}_collision_{k}">')
            out.append(f"      {origin_xml(X)}")
            out.append(f"      <geometry>{geom}</geometry>")
            out.append(f"      {_proximity_xml(kind)}")
            out.append("    </collision>")
        out.append("  </link>")
    for j in joints:
        effort = ACTUATOR_GAINS[j.name][2] if j.name in ACTUATOR_GAINS else MIMIC_EFFORT
        out.append(f'  <joint name="{j.name}" type="revolute">')
        out.append(f'    <parent link="{j.parent}"/>')
        out.append(f'    <child link="{j.child}"/>')
        out.append(f"    {origin_xml(j.X_PJ)}")
        out.append(f'    <axis xyz="{vec(j.axis)}"/>')
        out.append(
            f'    <limit lower="{fmt(j.lower)}" upper="{fmt(j.upper)}" velocity="{fmt(j.velocity)}" '
            f'effort="{fmt(effort)}"/>'
        )
        out.append(f'    <dynamics damping="{fmt(JOINT_DAMPING)}"/>')
        if j.mimic is not None:
            out.append(f'    <mimic joint="{j.mimic[0]}" multiplier="{fmt(j.mimic[1])}" offset="{fmt(j.mimic[2])}"/>')
        out.append("  </joint>")
    for name in ACTUATED_JOINTS:
        p, d, _ = ACTUATOR_GAINS[name]
        out.append(f'  <transmission name="{name}_transmission">')
        out.append("    <type>transmission_interface/SimpleTransmission</type>")
        out.append(f'    <joint name="{name}"><hardwareInterface>EffortJointInterface</hardwareInterface></joint>')
        out.append(f'    <actuator name="{name}_actuator">')
        out.append(f'      <drake:controller_gains p="{fmt(p)}" d="{fmt(d)}"/>')
        out.append("    </actuator>")
        out.append("  </transmission>")
    # The hand's own links never collide with each other (self-contact is not modelled).
    out.append('  <drake:collision_filter_group name="svh_all_links">')
    for name in ordered:
        out.append(f'    <drake:member link="{name}"/>')
    out.append('    <drake:ignored_collision_filter_group name="svh_all_links"/>')
    out.append("  </drake:collision_filter_group>")
    out.append("</robot>")
    return "\n".join(out) + "\n"


def generate(reference_dir: str | Path) -> tuple[str, dict[str, Body], list[Joint]]:
    """Read the vendor reference, fit primitives and return (URDF text, bodies, joints)."""
    vendor = read_vendor_urdf(reference_dir)
    bodies, joints = collapse_fixed_joints(vendor)
    missing = set(LINK_NAMES.values()) - set(bodies)
    if missing:
        raise ModelFileError(f"vendor URDF lacks links for {sorted(missing)}")
    fit_primitives(bodies)
    assign_inertia(bodies)
    note = (
        "Kinematics (origins, axes, limits, mimic factors) from the Schunk SVH vendor URDF (FZI schunk_svh_driver,"
        " LGPL); collision primitives fitted to its link meshes by tools/fitting.py."
    )
    return build_urdf(bodies, joints, note), bodies, joints


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reference", required=True, help="folder with the vendor svh_right.urdf and meshes/")
    ap.add_argument("--out", required=True, help="output folder (svh_right.urdf is written there)")
    args = ap.parse_args(argv)
    try:
        text, bodies, _ = generate(args.reference)
    except (InputError, ModelFileError) as exc:
        sys.stderr.write(f"svh_model: {exc}\n")
        return 2
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_bytes(out / "svh_right.urdf", text.encode())
    total = sum(b.mass for b in bodies.values())
    sys.stdout.write(f"wrote {out / 'svh_right.urdf'}: {len(bodies)} links, total mass {total:.3f} kg\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
