"""The force controller step record (rns_ros.control.force.status)."""

from __future__ import annotations

import numpy as np
import pytest
from force_cases import LWR, one_step

from rns_ros.control.contact_topics import ERROR_LABELS
from rns_ros.control.force.controller import ForceTeleopController
from rns_ros.control.force.settings import ForceControlSettings


def test_error_sample_layout():
    controller = ForceTeleopController(LWR, ForceControlSettings())
    out = one_step(controller, t=0.25)
    sample = out.error_sample()
    assert sample.shape == (len(ERROR_LABELS),)
    assert np.isfinite(sample).all()
    assert sample[0] == pytest.approx(0.25)
    np.testing.assert_allclose(sample[10:13], out.normal)
