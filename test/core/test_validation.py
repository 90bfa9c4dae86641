"""rns_ros.core.validation.short_repr: values in error messages are cut, with their length, at a
cost bounded whatever the value (a shared YAML structure can stand for billions of items)."""

from __future__ import annotations

import time

import numpy as np
import pytest

from rns_ros.core.errors import ConfigError, InputError
from rns_ros.core.validation import as_vector, positive, short_repr


@pytest.mark.parametrize(
    "value", ["camera", 1.5, -3, None, True, [1, 2, "a"], {"b": 1, "a": [2.5]}, (1,)]
)
def test_a_short_value_is_its_repr(value):
    assert short_repr(value) == repr(value)


def test_a_long_string_is_cut_and_its_length_said():
    text = short_repr("a" * 5000)
    assert text == "'" + "a" * 76 + "... (str of 5000 characters)"
    assert len(short_repr("a" * 5000, limit=20)) < 50


def test_a_long_list_is_cut_and_its_length_said():
    text = short_repr(list(range(1000)))
    assert text.startswith("[0, 1, 2, ")
    assert text.endswith("...] (list of 1000 items)")
    assert len(text) <= 80 + len(" (list of 1000 items)")


def test_a_shared_nested_value_costs_no_more_than_a_small_one():
    """9 ** 9 leaves by sharing, as nested YAML aliases build them: repr would never end."""
    value = ["lol"] * 9
    for _ in range(8):
        value = [value] * 9
    start = time.process_time()
    text = short_repr(value)
    assert time.process_time() - start < 0.1
    assert text.endswith("(list of 9 items)")
    assert len(text) < 120


def test_a_huge_integer_is_named_by_its_size():
    assert short_repr(2**20000) == "<int of 20001 bits>"


def test_the_edge_checks_cut_the_value_they_name():
    with pytest.raises(InputError, match=r"\(str of 10000 characters\)$"):
        as_vector("x" * 10000, 3, "axis")
    with pytest.raises(ConfigError, match=r"dt must be a finite number > 0 \[s\], got <int of"):
        positive(10**400, "dt", "[s]")
    with pytest.raises(ConfigError, match=r"got 'fast'$"):
        positive("fast", "dt", "[s]")
    np.testing.assert_array_equal(as_vector([1, 2, 3], 3, "axis"), [1.0, 2.0, 3.0])
