"""Time-tagged commands: execution time, late and future stamps refused."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from rns_ros.control.time_tags import TimeTags
from rns_ros.core.errors import ConfigError


def test_a_command_acts_its_execution_delay_after_its_stamp():
    tags = TimeTags(execution_delay=3.5)
    assert tags.execution_time(10.0) == 13.5


@given(
    delay=st.floats(0.0, 20.0),
    link=st.floats(0.0, 30.0),
    late=st.floats(0.01, 2.0),
    stamp=st.floats(0.0, 1e5),
)
def test_taken_exactly_when_the_link_kept_to_the_budget(delay, link, late, stamp):
    tags = TimeTags(execution_delay=delay, late_tolerance=late)
    refusal = tags.refusal(stamp, stamp + link)
    within = link <= delay + late
    # a 1 ulp band at the boundary: the sum stamp + link rounds
    if abs(link - (delay + late)) > 1e-9 * max(1.0, stamp):
        assert (refusal is None) == within, refusal


def test_late_and_future_stamps_are_refused_with_the_numbers():
    tags = TimeTags(execution_delay=3.0, late_tolerance=0.5, future_tolerance=0.05)
    assert tags.refusal(100.0, 103.5) is None
    late = tags.refusal(100.0, 104.0)
    assert "received 1.000 s after its execution time" in late
    assert "execution_delay 3 s; late_tolerance 0.5 s" in late
    future = tags.refusal(100.2, 100.0)
    assert "stamped 0.200 s in the future" in future
    assert tags.refusal(100.04, 100.0) is None  # within the clock tolerance
    assert "not a finite time" in tags.refusal(math.nan, 100.0)


@pytest.mark.parametrize(
    ("values", "message"),
    [
        ({"execution_delay": -1.0}, r"execution_delay must be in \[0, 1200\] s, got -1.0"),
        ({"execution_delay": math.inf}, r"execution_delay must be in \[0, 1200\] s, got inf"),
        ({"late_tolerance": 0.0}, r"late_tolerance must be finite and > 0 s, got 0.0"),
        ({"future_tolerance": math.nan}, r"future_tolerance must be finite and > 0 s, got nan"),
    ],
)
def test_bad_settings_name_the_value_and_the_range(values, message):
    with pytest.raises(ConfigError, match=message):
        TimeTags(**values)
