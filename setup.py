"""Build script of the ``rns_ros`` ament_python package (colcon / pip)."""

import os

from setuptools import find_packages, setup

PACKAGE_NAME = "rns_ros"

# Executables installed into lib/rns_ros/ (so `ros2 run rns_ros <name>` finds them) and, by
# pip, into the virtualenv's bin/. Add simulator / controller nodes here.
CONSOLE_SCRIPTS = [
    "rns_demo = rns_ros.apps.demo:main",
    "rns_simulator = rns_ros.nodes.simulator:main",
    "rns_controller = rns_ros.nodes.controller:main",
    "rns_force_controller = rns_ros.nodes.force_controller:main",
    "rns_ptp = rns_ros.nodes.ptp:main",
    "rns_attitude_control = rns_ros.nodes.attitude_control:main",
    "rns_link = rns_ros.nodes.link:main",
    "rns_predictor = rns_ros.nodes.predictor:main",
    "rns_rerun_logger = rns_ros.nodes.rerun_logger:main",
    "rns_operator = rns_ros.nodes.operator:main",
    "rns_teleop_keyboard = rns_ros.nodes.teleop_keyboard:main",
    "rns_teleop_spacemouse = rns_ros.nodes.teleop_spacemouse:main",
    "rns_observer = rns_ros.apps.observer:main",
    "rns_param = rns_ros.apps.param:param_main",
    "rns_topic = rns_ros.apps.topic:topic_main",
    "rns_service = rns_ros.apps.service:service_main",
    "rns_reproduce = rns_ros.apps.reproduce:main",
    "rns_model = rns_ros.apps.model_check:main",
    "rns_bag = rns_ros.apps.bag:main",
]

HERE = os.path.dirname(os.path.abspath(__file__))


def tree_data_files(directory, share_prefix="share/" + PACKAGE_NAME):
    """Return ``data_files`` entries installing every file under ``directory``.

    Sub-directories are preserved: ``config/urdf/arm.urdf`` is installed as
    ``share/rns_ros/config/urdf/arm.urdf``. Paths are relative to this file (setuptools and
    colcon require relative sources) and sorted so builds are reproducible. A missing
    directory yields no entries.
    """
    entries = []
    for dirpath, dirnames, filenames in os.walk(os.path.join(HERE, directory)):
        dirnames.sort()
        if filenames:
            rel_dir = os.path.relpath(dirpath, HERE)
            files = [os.path.join(rel_dir, name) for name in sorted(filenames)]
            entries.append((os.path.join(share_prefix, rel_dir), files))
    return entries


setup(
    name=PACKAGE_NAME,
    version="0.1.0",
    packages=find_packages(exclude=["test", "test.*"]),
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + PACKAGE_NAME]),
        ("share/" + PACKAGE_NAME, ["package.xml"]),
        *tree_data_files("config"),
    ],
    # Runtime dependencies are pinned in requirements.txt (pip) / package.xml (rosdep);
    # declaring them here would make colcon/pip try to resolve them again.
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="rns_ros developers",
    maintainer_email="rns_ros@example.com",
    description=(
        "Reactionless (Reaction Null-Space) teleoperation of free-floating space manipulators"
    ),
    license="Apache-2.0",
    tests_require=["pytest"],
    entry_points={
        "console_scripts": CONSOLE_SCRIPTS,
    },
)
