"""rns_ros.core.yaml_input: user YAML is measured while it is composed, so that a "billion laughs"
(aliases of aliases, nested inside a valid key's value) is refused before anything is expanded;
a few aliases, as hand-written files use them, still load, into what yaml.safe_load builds."""

from __future__ import annotations

import time
import tracemalloc

import pytest
import yaml
from rns_testing import BOMB_KEYS, alias_bomb_model

from rns_ros.core.config import load_model_config
from rns_ros.core.errors import ConfigError
from rns_ros.core.yaml_input import (
    MAX_YAML_ALIASES,
    MAX_YAML_BYTES,
    MAX_YAML_NODES,
    load_yaml,
    read_yaml_file,
)
from rns_ros.resources import config_dir

#: Peak Python memory while a bomb is read and refused [bytes]: a few kB of text and nodes.
REFUSAL_MEMORY = 5_000_000
#: CPU time to read and refuse a bomb [s] (about a millisecond).
REFUSAL_CPU = 0.5


@pytest.fixture(scope="module")
def urdf():
    return load_model_config(config_dir() / "model.yaml")[0]


@pytest.mark.parametrize("key", BOMB_KEYS)
def test_an_alias_bomb_in_a_model_key_is_refused_before_it_is_expanded(key, urdf, tmp_path):
    text = alias_bomb_model(key, urdf)  # 9 ** 9 strings once expanded
    assert text.count("*") < MAX_YAML_ALIASES  # refused by what the aliases stand for
    path = tmp_path / "bomb.yaml"
    path.write_text(text)
    tracemalloc.start()
    start = time.process_time()
    try:
        with pytest.raises(ConfigError) as caught:
            load_model_config(path)
        cpu = time.process_time() - start
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    message = str(caught.value)
    assert message.startswith(f"{path}: more than {MAX_YAML_NODES} YAML nodes"), message
    assert "aliases expanded" in message
    assert "\n" not in message
    assert len(message) < 300
    assert peak < REFUSAL_MEMORY
    assert cpu < REFUSAL_CPU


def test_more_aliases_than_the_limit_are_refused():
    aliases = ", ".join(["*x"] * MAX_YAML_ALIASES)
    assert load_yaml(f"a: &x 1\nb: [{aliases}]\n", "file")["b"] == [1] * MAX_YAML_ALIASES
    with pytest.raises(ConfigError, match=rf"^file: more than {MAX_YAML_ALIASES} YAML aliases"):
        load_yaml(f"a: &x 1\nb: [{aliases}, *x]\n", "file")


@pytest.mark.parametrize("text", ["a: &a [1, *a]\n", "a: &a {b: *a}\n"])
def test_an_alias_inside_its_own_anchor_is_refused(text):
    with pytest.raises(ConfigError, match=r"alias \*a at line 1 is inside its own anchor"):
        load_yaml(text, "file")


def test_a_long_document_without_aliases_is_refused_at_the_node_limit():
    items = ", ".join(["1"] * MAX_YAML_NODES)
    with pytest.raises(ConfigError, match=rf"more than {MAX_YAML_NODES} YAML nodes"):
        load_yaml(f"[{items}]", "file")
    assert len(load_yaml(f"[{', '.join(['1'] * (MAX_YAML_NODES - 1))}]", "file")) == (
        MAX_YAML_NODES - 1
    )


def test_a_file_over_the_size_limit_is_refused(tmp_path):
    path = tmp_path / "big.yaml"
    path.write_text("# " + "x" * MAX_YAML_BYTES + "\na: 1\n")
    size = path.stat().st_size
    with pytest.raises(ConfigError) as caught:
        read_yaml_file(path, "model config")
    assert str(caught.value) == (
        f"{path}: {size} bytes, over the limit of {MAX_YAML_BYTES} bytes for a model config"
    )
    with pytest.raises(ConfigError, match=rf"bytes of YAML, over the limit of {MAX_YAML_BYTES}"):
        load_yaml("x" * (MAX_YAML_BYTES + 1), "the message")


def test_a_model_yaml_with_a_few_aliases_loads(urdf, tmp_path):
    path = tmp_path / "model.yaml"
    path.write_text(
        f"urdf: {urdf}\n"
        "positioning_joints: [&first joint_1, joint_2, joint_3, joint_4]\n"
        "wrist_joints: &wrist [joint_5, joint_6, joint_7]\n"
        "controlled_joints: [*first, joint_2, joint_3, joint_4, joint_5, joint_6, joint_7]\n"
        "initial_joint_positions: {joint_2: &bend -0.5, joint_4: *bend}\n"
    )
    _, spec = load_model_config(path)
    assert spec.controlled_joints == tuple(f"joint_{i}" for i in range(1, 8))
    assert spec.wrist_joints == ("joint_5", "joint_6", "joint_7")
    assert spec.initial_joint_positions == {"joint_2": -0.5, "joint_4": -0.5}


def test_the_shipped_files_load_as_safe_load_reads_them():
    files = sorted(config_dir().rglob("*.yaml"))
    assert len(files) > 10
    for path in files:
        text = path.read_text()
        assert load_yaml(text, str(path)) == yaml.safe_load(text), path
    merged = "base: &b {x: 1, y: 2}\nother:\n  <<: *b\n  y: 3\nwhen: 2001-12-14\nn: 0x1f\n"
    assert load_yaml(merged, "x") == yaml.safe_load(merged)


@pytest.mark.parametrize(
    "text", ["a: [1\n", "a: *missing\n", "--- 1\n--- 2\n", "a: !!python/object:os.system x\n"]
)
def test_what_is_not_safe_yaml_is_a_yaml_error(text):
    with pytest.raises(yaml.YAMLError):
        load_yaml(text, "file")


def test_an_overlong_integer_is_invalid_yaml_not_a_traceback(urdf, tmp_path):
    path = tmp_path / "model.yaml"
    path.write_text(f"urdf: {urdf}\ninitial_joint_positions: {{joint_1: {'1' * 5000}}}\n")
    with pytest.raises(ConfigError, match=r"not valid YAML: .*integer of 5000 characters is too"):
        load_model_config(path)


def test_an_integer_beyond_float_is_not_a_finite_number(urdf, tmp_path):
    path = tmp_path / "model.yaml"
    path.write_text(f"urdf: {urdf}\ninitial_joint_positions: {{joint_1: 0b{'1' * 2000}}}\n")
    with pytest.raises(ConfigError, match=r"'joint_1' must be a finite number, got <int of 2000"):
        load_model_config(path)


def test_a_large_value_is_cut_in_the_error_message(urdf, tmp_path):
    path = tmp_path / "model.yaml"
    items = ", ".join(["frame"] * (MAX_YAML_NODES // 2))
    path.write_text(f"urdf: {urdf}\ncamera_frame: [{items}]\n")
    with pytest.raises(ConfigError) as caught:
        load_model_config(path)
    message = str(caught.value)
    assert "'camera_frame' must be a frame name, got ['frame', " in message
    assert message.endswith(f"(list of {MAX_YAML_NODES // 2} items)")
    assert len(message) < len(str(path)) + 200


def test_an_unreadable_or_overlong_path_is_one_line(tmp_path):
    (tmp_path / "folder.yaml").mkdir()
    with pytest.raises(ConfigError, match="model config not found"):
        read_yaml_file(tmp_path / "folder.yaml", "model config")
    with pytest.raises(ConfigError, match="cannot read the model config: File name too long"):
        read_yaml_file(tmp_path / ("x" * 300), "model config")
    binary = tmp_path / "binary.yaml"
    binary.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(ConfigError, match="cannot read the model config: 'utf-8' codec"):
        read_yaml_file(binary, "model config")
