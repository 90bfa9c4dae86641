"""Simulation of the free-floating robot (fixed-step RK4, kinematic and dynamic modes); later also
reaction wheels and contact. Built on :mod:`rns_ros.core` only; no rclpy or rerun.
"""
