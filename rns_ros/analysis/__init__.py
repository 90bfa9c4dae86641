"""Analyses on top of control and simulation: the in-process closed loop, the figures of a recorded
run, the planar vector field of chapter 3, and the reproduction registry (``rns_reproduce``).
No rclpy or rerun.
"""
