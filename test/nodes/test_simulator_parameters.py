"""The parameter tables of rns_simulator: shared specs, enum-derived choices, on-set checks."""

from rclpy.parameter import Parameter

from rns_ros.nodes import contact_simulator_parameters as contact
from rns_ros.nodes import simulator_parameters as free_floating
from rns_ros.sim.free_floating import SimulationMode


def test_mode_choices_are_the_simulation_modes_and_contact():
    spec = free_floating.SPECS["mode"]
    assert spec.choices == (*(mode.value for mode in SimulationMode), free_floating.CONTACT_MODE)
    assert contact.SPECS["mode"].choices == (free_floating.CONTACT_MODE,)


def test_shared_specs_differ_only_in_defaults_and_bounds():
    for name in ("mode", "step_size", "publish_rate", "real_time_factor", "lockstep_period"):
        assert contact.SPECS[name].description == free_floating.SPECS[name].description
        assert contact.SPECS[name].read_only == free_floating.SPECS[name].read_only
    assert contact.NODE_NAME == free_floating.NODE_NAME


def test_on_set_check_rejects_what_a_spec_refuses_and_passes_the_rest():
    specs = free_floating.SPECS
    bad = free_floating.check_parameter_changes(specs, [Parameter("mode", value="teleport")])
    assert not bad.successful
    assert "'mode' must be one of" in bad.reason
    good = [Parameter("real_time_factor", value=0.0), Parameter("use_sim_time", value=True)]
    assert free_floating.check_parameter_changes(specs, good).successful


def test_the_default_start_is_the_default_models_initial_configuration():
    """config/model.yaml's initial_joint_positions (what rns_model check looks at) and the
    simulator's default start are the same pose, the thesis' satellite observation."""
    import numpy as np

    from rns_ros.core import load_model
    from rns_ros.nodes.simulator_parameters import SATELLITE_OBSERVATION_RAD
    from rns_ros.resources import default_model_config

    robot = load_model(default_model_config())
    np.testing.assert_array_equal(robot.initial_theta, SATELLITE_OBSERVATION_RAD)
