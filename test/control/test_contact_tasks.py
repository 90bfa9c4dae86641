"""The chapter-6 task records (rns_ros.control.contact_tasks): profiles and validation."""

from __future__ import annotations

import pytest

from rns_ros.control.contact_tasks import ArcScenario, WallScenario, back_and_forth, force_profile
from rns_ros.core.errors import ConfigError


def test_profiles():
    assert back_and_forth(0.0, 1.0, 2) == (0.0, 0.0, 0.0)
    assert back_and_forth(1.0, 1.0, 2)[0] == pytest.approx(1.0)
    assert back_and_forth(1.5, 1.0, 2)[0] == pytest.approx(0.5)
    assert back_and_forth(1.5, 1.0, 2)[1] < 0.0  # on the way back
    assert back_and_forth(5.0, 1.0, 2) == pytest.approx((0.0, 0.0, 0.0))  # held at the end
    assert back_and_forth(5.0, 1.0, 3)[0] == pytest.approx(1.0)
    assert force_profile(0.5, 10.0, 1.0) == pytest.approx(5.0)
    assert force_profile(3.0, 10.0, 1.0) == 10.0


@pytest.mark.parametrize(
    "make",
    [
        lambda: ArcScenario(radius=0.0),
        lambda: ArcScenario(radius=float("nan")),
        lambda: ArcScenario(half_cycle=-1.0),
        lambda: ArcScenario(half_cycles=0),
        lambda: ArcScenario(half_cycles=1.5),
        lambda: ArcScenario(start_angle_deg=200.0, end_angle_deg=200.0),
        lambda: ArcScenario(seed_deg=(1.0, 2.0)),
        lambda: ArcScenario(force=-1.0),
        lambda: ArcScenario(center=(0.0, "a")),
        lambda: WallScenario(initial_deg=(0.0,) * 6),
        lambda: WallScenario(normal=(0.0, 0.0, 0.0)),
        lambda: WallScenario(stroke=0.0),
        lambda: WallScenario(strokes=0),
        lambda: WallScenario(length=-0.1),
        lambda: WallScenario(force_ramp=0.0),
    ],
)
def test_bad_scenario_parameters_raise_config_error(make):
    with pytest.raises(ConfigError):
        make()
