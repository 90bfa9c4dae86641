"""ROS 2 nodes of rns_ros: message conversion around :mod:`rns_ros.core`, nothing more."""
