"""The programs of rns_ros (rns_demo, rns_observer, rns_reproduce, rns_param, rns_topic,
rns_service, rns_bag): argument parsing and output around the libraries. The ROS 2 node
executables live in :mod:`rns_ros.nodes`."""
