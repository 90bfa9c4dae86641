"""Teleoperation from the ground (beyond the thesis): the space link between operator and
spacecraft, and the predictive display's model of the arm. Built on :mod:`rns_ros.core`,
:mod:`rns_ros.control` and :mod:`rns_ros.sim`; no rclpy or rerun.
"""
