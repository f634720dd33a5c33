"""The SVH hand model: parses, has the vendor's kinematics, fits, actuators and couplers."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlantConfig
from pydrake.systems.framework import DiagramBuilder

from catgrasp_drake.errors import InputError
from catgrasp_drake.robot import models
from tools import fitting, svh_model

REFERENCE = Path(__file__).resolve().parents[2].parent / "shared" / "reference" / "schunk_svh"


@pytest.fixture(scope="module")
def reference_dir() -> Path:
    if not (REFERENCE / "svh_right.urdf").is_file():
        pytest.skip("../shared/reference/schunk_svh not present")
    return REFERENCE


def _sap_plant():
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlant(
        MultibodyPlantConfig(time_step=5e-3, discrete_contact_approximation="sap",
                             contact_model="hydroelastic_with_fallback"),
        builder,
    )
    return builder, plant, scene_graph


@pytest.fixture(scope="module")
def hand_plant():
    builder, plant, scene_graph = _sap_plant()
    hand = models.add_hand(plant)
    plant.Finalize()
    return plant, hand


def test_hand_parses_with_actuators_and_couplers(hand_plant):
    plant, hand = hand_plant
    assert plant.num_actuators(hand) == 9
    assert plant.num_constraints() == 11
    assert plant.num_positions(hand) == 7 + 20  # floating base + 9 actuated + 11 mimic joints
    names = [plant.get_joint_actuator(i).joint().name() for i in plant.GetJointActuatorIndices(hand)]
    assert tuple(names) == models.HAND_ACTUATED_JOINTS
    for i in plant.GetJointActuatorIndices(hand):
        actuator = plant.get_joint_actuator(i)
        kp, kd, effort = models.HAND_PD_GAINS[actuator.joint().name()]
        assert actuator.has_controller()
        assert actuator.get_controller_gains().p == kp and actuator.get_controller_gains().d == kd
        assert actuator.effort_limit() == effort
    for name in models.HAND_LINKS:
        plant.GetBodyByName(name, hand)
    assert models.HAND_BASE_LINK in models.HAND_LINKS and models.INDEX_DISTAL_LINK in models.HAND_LINKS
    assert set(models.FINGER_DISTAL_LINKS.values()) <= set(models.HAND_LINKS)
    total = sum(plant.GetBodyByName(n, hand).default_mass() for n in models.HAND_LINKS)
    assert total == pytest.approx(1.3, abs=1e-6)


def test_hand_collision_geometry_is_compliant_hydroelastic():
    root = ET.parse(models.HAND_URDF_PATH).getroot()
    collisions = root.findall("link/collision")
    assert len(collisions) >= len(models.HAND_LINKS)
    for col in collisions:
        shape = col.find("geometry")[0].tag
        assert shape in ("capsule", "box", "cylinder")
        props = col.find("{http://drake.mit.edu}proximity_properties")
        assert props.find("{http://drake.mit.edu}compliant_hydroelastic") is not None
        modulus = float(props.find("{http://drake.mit.edu}hydroelastic_modulus").get("value"))
        assert 1e6 <= modulus <= 1e7
        assert float(props.find("{http://drake.mit.edu}mu_dynamic").get("value")) == pytest.approx(1.0)
    # Every finger link is a single fitted capsule; the palm bodies have boxes.
    for link in root.findall("link"):
        shapes = [c.find("geometry")[0].tag for c in link.findall("collision")]
        if link.get("name") in ("svh_base_link", "svh_palm_flex_link"):
            assert "box" in shapes
        else:
            assert shapes == ["capsule"]


def test_hand_requires_sap():
    builder = DiagramBuilder()
    plant, _ = AddMultibodyPlant(MultibodyPlantConfig(time_step=5e-3, discrete_contact_approximation="tamsi"), builder)
    with pytest.raises(InputError, match="sap"):
        models.add_hand(plant)


def test_two_hands_with_distinct_names():
    _, plant, _ = _sap_plant()
    a = models.add_hand(plant, model_name="left_svh")
    b = models.add_hand(plant, model_name="right_svh")
    assert plant.GetModelInstanceName(a) == "left_svh" and plant.GetModelInstanceName(b) == "right_svh"
    assert plant.num_constraints() == 22


def test_limits_and_mimic_factors_match_reference(reference_dir, hand_plant):
    plant, hand = hand_plant
    vendor = svh_model.read_vendor_urdf(reference_dir)
    mimics = models.hand_mimic_joints()
    assert len(mimics) == 11
    checked = 0
    for vendor_name, project_name in svh_model.JOINT_NAMES.items():
        vj = vendor.joints[vendor_name]
        joint = plant.GetJointByName(project_name, hand)
        assert joint.position_lower_limits()[0] == pytest.approx(vj.lower, abs=1e-12)
        assert joint.position_upper_limits()[0] == pytest.approx(vj.upper, abs=1e-12)
        if vj.mimic is None:
            assert project_name not in mimics
        else:
            leader, mult, offset = mimics[project_name]
            assert leader == svh_model.JOINT_NAMES[vj.mimic[0]]
            assert mult == pytest.approx(vj.mimic[1], abs=1e-12)
            assert offset == pytest.approx(vj.mimic[2], abs=1e-12)
        checked += 1
    assert checked == 20


def test_kinematics_match_reference_forward_kinematics(reference_dir, hand_plant):
    """Collapsing fixed joints kept every frame: body poses agree with the vendor model at a bent configuration."""
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import MultibodyPlant

    ref = MultibodyPlant(0.0)
    Parser(ref).AddModels(str(reference_dir / "svh_right.urdf"))
    ref.Finalize()
    ref_context = ref.CreateDefaultContext()
    plant, hand = hand_plant
    context = plant.CreateDefaultContext()
    rng = np.random.default_rng(4)
    for vendor_name, project_name in svh_model.JOINT_NAMES.items():
        vj = ref.GetJointByName(vendor_name)
        q = rng.uniform(vj.position_lower_limits()[0], vj.position_upper_limits()[0])
        vj.set_angle(ref_context, q)
        plant.GetJointByName(project_name, hand).set_angle(context, q)
    for vendor_link, project_link in svh_model.LINK_NAMES.items():
        X_ref = ref.GetBodyByName(vendor_link).EvalPoseInWorld(ref_context)
        X = plant.GetBodyByName(project_link, hand).EvalPoseInWorld(context)
        assert np.allclose(X.GetAsMatrix4(), X_ref.GetAsMatrix4(), atol=1e-9), project_link


_NUMBER = re.compile(r"-?\d+(?:\.\d+)?(?:e[-+]?\d+)?")


def test_generator_reproduces_committed_urdf(reference_dir):
    """Same text, every number equal to 1e-6 relative or 10 nm (the fits' last digits follow the numpy/scipy build)."""
    text, bodies, joints = svh_model.generate(reference_dir)
    committed = models.HAND_URDF_PATH.read_text()
    stale = "models/svh/svh_right.urdf is stale: rerun python -m tools.svh_model"
    assert _NUMBER.sub("#", text) == _NUMBER.sub("#", committed), stale
    new, old = (np.array([float(v) for v in _NUMBER.findall(t)]) for t in (text, committed))
    np.testing.assert_allclose(new, old, rtol=1e-6, atol=1e-8, err_msg=stale)
    assert len(joints) == 20


def test_fitted_primitives_cover_their_meshes(reference_dir):
    import trimesh

    vendor = svh_model.read_vendor_urdf(reference_dir)
    for path, _ in vendor.links["right_hand_l"] + vendor.links["right_hand_t"] + vendor.links["right_hand_a"]:
        v = np.asarray(trimesh.load(str(path), force="mesh").vertices)
        cap = fitting.fit_capsule(v)
        # Distance of every vertex to the capsule's segment is at most the radius.
        a = cap.p_BC - 0.5 * cap.length * cap.axis_B
        t = np.clip((v - a) @ cap.axis_B, 0.0, cap.length)
        d = np.linalg.norm(v - (a + np.outer(t, cap.axis_B)), axis=1)
        assert d.max() <= cap.radius * (1 + 1e-6)
        # And it is tight: some vertex touches the surface.
        assert d.max() >= cap.radius * (1 - 1e-6)
        # A finger phalanx is elongated: the capsule runs along it.
        assert cap.length > cap.radius


def test_min_enclosing_circle_exact():
    pts = np.array([[0.0, 0.0], [2.0, 0.0], [1.0, 0.1], [1.0, -0.2]])
    c, r = fitting.min_enclosing_circle(pts)
    assert np.allclose(c, [1.0, 0.0]) and r == pytest.approx(1.0)
    tri = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, np.sqrt(3) / 2]])
    c, r = fitting.min_enclosing_circle(tri)
    assert r == pytest.approx(1 / np.sqrt(3))


def test_boxes_along_axis_cover_points():
    rng = np.random.default_rng(0)
    # An L-shaped cloud: a wide slab at the bottom and a narrow column on top.
    pts = np.vstack([rng.uniform([0, 0, 0], [0.06, 0.06, 0.05], (400, 3)),
                     rng.uniform([0, 0, 0.05], [0.06, 0.02, 0.12], (400, 3))])
    boxes = fitting.fit_boxes_along_axis(pts)
    assert 2 <= len(boxes) <= 3
    covered = np.zeros(len(pts), bool)
    for b in boxes:
        lo, hi = b.p_BC - b.size / 2 - 1e-12, b.p_BC + b.size / 2 + 1e-12
        covered |= np.all((pts >= lo) & (pts <= hi), axis=1)
    assert covered.all()
    assert sum(b.volume for b in boxes) < 0.8 * fitting.fit_box(pts).volume
