"""The per-step logic of ``rns_force_controller``: operator motion/force teleoperation of a
fixed-base arm in contact, thesis chapter 6, without ROS (docs/part2_ros.md)."""
