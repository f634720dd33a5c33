"""PHYSICS: the hand closes on a free 4 cm cylinder, lifts it off the table and holds it for 2 s.

The setting every later success figure relies on: Drake 1.51, SAP, hydroelastic
with fallback, 5 ms steps; the cylinder (0.3 kg as specified, and 1.0 kg; rigid hydroelastic, mu 0.8)
stands on a table, about 4 mm clear of the preshaped hand; the hand, on a PD-driven lift, closes its "cylinder"
posture with the effort-limited PD actuators, lifts by 5 cm and holds. Gravity
acts along the cylinder axis, so only the squeeze and friction hold it.
"""

from __future__ import annotations

import pytest

from catgrasp_drake.robot.grasp_rig import CylinderGraspParams, simulate_cylinder_grasp


@pytest.mark.slow
@pytest.mark.parametrize("mass", [0.3, 1.0])
def test_hand_holds_cylinder_against_gravity(mass):
    params = CylinderGraspParams(mass=mass)
    assert params.radius == 0.02 and params.hold_time >= 2.0 and params.lift_height >= 0.05
    result = simulate_cylinder_grasp(params)
    # The grasp starts from a clear preshape (nothing wedged at t = 0).
    assert result.initial_hand_contacts == []
    # Held by the hand alone: off the table by (about) the lift height, touching no table.
    assert result.height_above_table > 0.8 * params.lift_height
    assert not result.touches_table
    # No slip during the 2 s hold, and little since closing.
    assert abs(result.drop_during_hold) < 0.01
    assert abs(result.drop_total) < 0.01
    # Power grasp: fingers AND thumb on the cylinder.
    assert result.touches_thumb, result.hand_links_in_contact
    assert result.touches_fingers, result.hand_links_in_contact
    # Coupler constraints hold while squeezing (follower = m * leader + offset).
    assert result.couplers_max_error < 2e-3


@pytest.mark.slow
def test_without_closing_the_cylinder_stays_on_the_table():
    """Negative control: the same motion with the hand left in its preshape does not lift the cylinder."""
    result = simulate_cylinder_grasp(CylinderGraspParams(close_to="preshape", hold_time=0.5))
    assert result.height_above_table < 0.005
    assert not result.touches_thumb
