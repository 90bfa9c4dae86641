"""config/spacenav.yaml: the spacenav driver's section uses the driver's own parameter names and
types and stays below the controller's speed limit; the controller's section is within its
parameter ranges."""

from __future__ import annotations

import math
from pathlib import Path

import yaml

from rns_ros.nodes.controller_parameters import SPECS

REPO = Path(__file__).resolve().parents[1]
#: The parameters ros-drivers/joystick_drivers' spacenav node declares (src/spacenav.cpp, ROS 2),
#: with their types; it ignores any other name without a word.
UPSTREAM_PARAMETERS = {
    "full_scale": float,
    **{f"{kind}_scale/{axis}": float for kind in ("angular", "linear") for axis in "xyz"},
    "static_count_threshold": int,
    "zero_when_static": bool,
    "static_trans_deadband": float,
    "static_rot_deadband": float,
    "use_twist_stamped": bool,
}
#: Largest axis value of spacenavd relative to full_scale at full deflection of the devices [-].
FULL_DEFLECTION = 1.0


def _sections() -> dict:
    return yaml.safe_load((REPO / "config" / "spacenav.yaml").read_text())


def test_the_driver_section_uses_upstream_names_and_types():
    driver = _sections()["spacenav"]["ros__parameters"]
    assert set(driver) <= set(UPSTREAM_PARAMETERS), "the driver would ignore the others"
    for name, value in driver.items():
        assert type(value) is UPSTREAM_PARAMETERS[name], name
    assert driver["zero_when_static"] is True  # a stuck cap ends in zeros
    assert all(driver[f"linear_scale/{axis}"] == 0.0 for axis in "xyz")


def test_a_full_twist_about_every_axis_stays_below_the_controller_limit():
    driver = _sections()["spacenav"]["ros__parameters"]
    limit = SPECS["max_angular_speed"].default
    full = [FULL_DEFLECTION * driver[f"angular_scale/{axis}"] for axis in "xyz"]
    assert 0.0 < math.hypot(*full) < limit


def test_the_controller_section_takes_plain_twists_in_the_camera_frame():
    controller = _sections()["rns_controller"]["ros__parameters"]
    assert controller == {"twist_stamped": False, "default_twist_frame": "camera"}
    for name, value in controller.items():
        assert type(value) is type(SPECS[name].default), name
