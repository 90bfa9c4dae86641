"""config/<node>.yaml mirrors the declared defaults of every node, its overlay files name only
declared parameters, and every description is one line."""

from __future__ import annotations

import importlib

import pytest
import yaml

from rns_ros.resources import config_dir

#: (module with the node's PARAMETERS, its config file).
DEFAULTS = (
    ("rns_ros.nodes.simulator_parameters", "simulator.yaml"),
    ("rns_ros.nodes.contact_simulator_parameters", "contact_simulator.yaml"),
    ("rns_ros.nodes.controller_parameters", "controller.yaml"),
    ("rns_ros.nodes.ptp_parameters", "ptp.yaml"),
    ("rns_ros.nodes.force_controller_parameters", "force_controller.yaml"),
    ("rns_ros.nodes.attitude_control_parameters", "attitude_control.yaml"),
    ("rns_ros.nodes.link_parameters", "link.yaml"),
    ("rns_ros.nodes.predictor_parameters", "predictor.yaml"),
    ("rns_ros.nodes.operator_parameters", "operator.yaml"),
    ("rns_ros.nodes.rerun_logger_parameters", "rerun_logger.yaml"),
    ("rns_ros.nodes.teleop_keyboard_parameters", "teleop_keyboard.yaml"),
    ("rns_ros.nodes.teleop_spacemouse_parameters", "teleop_spacemouse.yaml"),
)
#: (module with the node's PARAMETERS, a config file that overrides some of them).
OVERLAYS = (("rns_ros.nodes.force_controller_parameters", "force_controller_arc.yaml"),)


def _values(file_name: str) -> dict:
    content = yaml.safe_load((config_dir() / file_name).read_text())
    return content["/**"]["ros__parameters"]


@pytest.mark.parametrize(("module", "file_name"), DEFAULTS)
def test_config_yaml_mirrors_the_declared_defaults(module, file_name):
    parameters = importlib.import_module(module).PARAMETERS
    assert _values(file_name) == {spec.name: spec.default for spec in parameters}


@pytest.mark.parametrize(("module", "file_name"), OVERLAYS)
def test_config_overlays_name_declared_parameters(module, file_name):
    parameters = importlib.import_module(module).PARAMETERS
    assert set(_values(file_name)) <= {spec.name for spec in parameters}


#: Longest description with its unit [characters]: `ros2 param describe` and the docs' tables
#: show one line; longer explanations belong in the node's page.
DESCRIPTION_LIMIT = 120


@pytest.mark.parametrize(("module", "file_name"), DEFAULTS)
def test_every_description_is_one_short_line(module, file_name):
    for spec in importlib.import_module(module).PARAMETERS:
        text = f"{spec.description} {spec.unit}".strip()
        assert "\n" not in text, spec.name
        assert len(text) <= DESCRIPTION_LIMIT, f"{spec.name}: {len(text)} characters"


@pytest.mark.parametrize(("module", "file_name"), DEFAULTS)
def test_every_parameter_is_declared_once(module, file_name):
    names = [spec.name for spec in importlib.import_module(module).PARAMETERS]
    assert len(names) == len(set(names)), sorted(name for name in names if names.count(name) > 1)
