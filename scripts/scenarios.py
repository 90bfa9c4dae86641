#!/usr/bin/env python3
"""Closed-loop figures of the thesis scenarios (controller core + simulator core, no ROS).

Usage:  .venv/bin/python scripts/scenarios.py [--scenario NAME ...] [--rate HZ] [--json PATH]

For each scenario in config/scenarios/ and each variant (dls, dls naive hold, sc, pinv,
conventional, dls in dynamic mode) prints: max base attitude deviation [deg], final camera
orientation error [deg], max rotation-axis error [deg], achieved rotation [deg], max wrist drift
[m], min sigma_min of J-bar, max DLS damping, speed-scale range, min det(J-bar J-bar^T) and when,
max servo error [rad]. Numbers, not tests: test/analysis/test_closed_loop.py asserts the physics.
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import asdict

from rns_ros.analysis.closed_loop import run_scenario
from rns_ros.control.scenario import load_scenario
from rns_ros.core import load_model
from rns_ros.resources import config_dir, default_model_config

VARIANTS = {
    "dls": {},
    "dls naive": {"hold_correction": "naive"},
    "sc": {"method": "sc"},
    "pinv": {"method": "pinv"},
    "conventional": {"method": "conventional"},
    "dls dynamic": {"mode": "dynamic"},
}
COLUMNS = (
    ("base [deg]", "max_base_deviation_deg", ".2e"),
    ("final err [deg]", "final_orientation_error_deg", ".3g"),
    ("axis err [deg]", "max_axis_error_deg", ".2e"),
    ("turned [deg]", "achieved_angle_deg", ".1f"),
    ("wrist [m]", "max_wrist_drift", ".3f"),
    ("sigma_min", "min_sigma", ".3f"),
    ("lambda2", "max_damping", ".2f"),
    ("scale min", "min_speed_scale", ".2f"),
    ("scale max", "max_speed_scale", ".2f"),
    ("det(JJ^T) min", "min_algorithmic_determinant", ".3f"),
    ("at [s]", "min_algorithmic_determinant_time", ".1f"),
    ("servo [rad]", "max_servo_error", ".1e"),
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", action="append", help="scenario name (default: all)")
    parser.add_argument("--rate", type=float, default=100.0, help="control rate [Hz]")
    parser.add_argument("--json", help="also write the figures as JSON here")
    args = parser.parse_args()
    robot = load_model(default_model_config())
    paths = sorted((config_dir() / "scenarios").glob("*.yaml"))
    if args.scenario:
        paths = [path for path in paths if path.stem in args.scenario]
    results = {}
    header = f"{'scenario / variant':<40}" + "".join(f"{title:>16}" for title, _, _ in COLUMNS)
    print(header)
    for path in paths:
        scenario = load_scenario(path)
        for variant, options in VARIANTS.items():
            start = time.perf_counter()
            result = run_scenario(robot, scenario, rate=args.rate, **options)
            results[f"{scenario.name}/{variant}"] = asdict(result)
            cells = "".join(f"{getattr(result, key):>16{fmt}}" for _, key, fmt in COLUMNS)
            print(f"{scenario.name + ' / ' + variant:<40}{cells}", flush=True)
            results[f"{scenario.name}/{variant}"]["wall_time_s"] = time.perf_counter() - start
    if args.json:
        with open(args.json, "w") as stream:
            json.dump(results, stream, indent=2)


if __name__ == "__main__":
    main()
