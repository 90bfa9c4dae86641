"""Parameter tables: settings built from parameter values, enum choices, the Markdown table."""

from __future__ import annotations

from dataclasses import dataclass, field

from rns_ros.control.controller import TwistFrame
from rns_ros.control.ptp import PtpMethod
from rns_ros.nodes.parameters import (
    ParameterSpec,
    choices_of,
    from_parameters,
    markdown_table,
    model_frame_names,
    twist_frame_names,
)


@dataclass(frozen=True)
class _Settings:
    rate: float = 1.0
    axes: tuple[str, ...] = ("x",)
    period: float = 0.1
    derived: int = field(init=False, default=0)


def test_settings_take_the_parameters_named_by_their_keywords():
    params = {"rate": 50.0, "axes": ["x", "y"], "world_frame": "world", "derived": 3}
    settings = from_parameters(_Settings, params, period=0.5)
    assert settings == _Settings(rate=50.0, axes=("x", "y"), period=0.5)
    assert from_parameters(_Settings, {}) == _Settings()


def test_choices_follow_the_enum_and_leave_out_the_excluded_members():
    assert choices_of(TwistFrame) == ("world", "base", "camera")
    assert "deploy" not in choices_of(PtpMethod, without=(PtpMethod.DEPLOY,))
    assert len(choices_of(PtpMethod, without=(PtpMethod.DEPLOY,))) == len(PtpMethod) - 1


def test_twist_frame_names_map_every_frame():
    params = {"world_frame": "w", "base_frame": "b", "camera_frame": "c"}
    names = twist_frame_names(params)
    assert names == {TwistFrame.WORLD: "w", TwistFrame.BASE: "b", TwistFrame.CAMERA: "c"}


def test_empty_twist_frames_come_from_the_model(tmp_path):
    def not_loaded():
        raise AssertionError("the model is loaded only for an empty frame")

    params = {"world_frame": "w", "base_frame": "b", "camera_frame": "c", "model_config": ""}
    assert twist_frame_names(params, not_loaded)[TwistFrame.CAMERA] == "c"
    empty = {**params, "base_frame": "", "camera_frame": ""}
    # the default arm's frames, read from its URDF (root link, camera link)
    assert twist_frame_names(empty)[TwistFrame.BASE] == "base_link"
    assert twist_frame_names(empty)[TwistFrame.CAMERA] == "camera"
    # another model: a camera frame named in its YAML
    from rns_ros.core.config import load_model_config
    from rns_ros.resources import default_model_config

    urdf, _ = load_model_config(default_model_config())
    model = tmp_path / "tool.yaml"
    model.write_text(f"urdf: {urdf}\ncamera_frame: wrist\nwrist_frame: null\n")
    names = twist_frame_names({**empty, "model_config": str(model), "base_frame": "sat"})
    assert names == {TwistFrame.WORLD: "w", TwistFrame.BASE: "sat", TwistFrame.CAMERA: "wrist"}
    assert model_frame_names(str(model)) == ("base_link", "wrist")


def test_the_table_has_one_row_per_parameter_with_its_limits():
    specs = (
        ParameterSpec("rate", 50.0, "Rate | of output", "[Hz]", 1.0, 1000.0, read_only=False),
        ParameterSpec("mode", "a", "Mode", choices=("a", "b")),
        ParameterSpec("axis", [0.0, 0.0, 1.0], "Axis", "[-]", -1.0, 1.0, length=(3,)),
        ParameterSpec("frame", "", "Frame"),
        ParameterSpec("on", True, "On"),
        ParameterSpec("names", ["x", "y"], "Names"),
    )
    lines = markdown_table(specs).splitlines()
    assert len(lines) == 2 + len(specs)
    assert lines[2] == r"| `rate` | double | `50.0` | Hz | [1, 1000] | no | Rate \| of output |"
    assert lines[3] == "| `mode` | string | `a` |  | `a`, `b` | yes | Mode |"
    axis = "| `axis` | double[] | `[0.0, 0.0, 1.0]` | - | [-1, 1]; length 3 | yes | Axis |"
    assert lines[4] == axis
    assert lines[5] == "| `frame` | string | `''` |  |  | yes | Frame |"
    assert lines[6] == "| `on` | bool | `true` |  |  | yes | On |"
    assert lines[7] == "| `names` | string[] | `[x, y]` |  |  | yes | Names |"


def test_a_node_logs_the_models_start_up_summary():
    """Every node that loads the model says which joints it drives, which it holds and what
    loading changed (the gripper arm: held fingers, the thesis satellite)."""
    from pathlib import Path

    from rns_ros.nodes.parameters import load_node_model

    lines = []

    class _Logger:
        def info(self, text):
            lines.append(text)

    class _Node:
        def get_logger(self):
            return _Logger()

    model = Path(__file__).parents[1] / "data" / "arms" / "gripper7" / "model.yaml"
    robot = load_node_model(_Node(), str(model))
    assert lines == robot.describe()
    assert any("g7_finger_joint1 = 0.02" in line for line in lines)
    assert any("thesis satellite" in line for line in lines)
