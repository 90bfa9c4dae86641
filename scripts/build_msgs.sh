#!/usr/bin/env bash
# Generate the ROS message packages rns_ros needs that have no PyPI wheel (msgs/: tf2_msgs, for
# /tf and /tf_static) into the virtual environment, with the PyPI ROS toolchain
# (requirements-msgs.txt: ament_cmake, rosidl generators), colcon and the system's cmake and C
# compiler. Skipped when the package is importable already (a full ROS 2 Jazzy install has it).
# Usage: scripts/build_msgs.sh VENV
set -euo pipefail
venv="$(cd "${1:?usage: build_msgs.sh VENV}" && pwd)"
py="$venv/bin/python"
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

if "$py" -c "import tf2_msgs.msg" 2>/dev/null; then
    echo "tf2_msgs: importable already, not generated"
    exit 0
fi
command -v cmake >/dev/null || { echo "error: cmake not found (needed to generate tf2_msgs)" >&2; exit 1; }

# The message wheels' CMake exports name the include folders of the machine that built them
# (/opt/python/cp311-cp311/...): point them at this interpreter's.
include="$("$py" -c 'import sysconfig; print(sysconfig.get_paths()["include"])')"
numpy_include="$("$py" -c 'import numpy; print(numpy.get_include())')"
grep -rlZ --include='*.cmake' '/opt/python/' "$venv/share" | xargs -0 -r sed -i \
    -e "s#/opt/python/[^;\"]*/site-packages/numpy/_core/include#$numpy_include#g" \
    -e "s#/opt/python/cp3[0-9]*-cp3[0-9]*/include/python3\.[0-9]*#$include#g"

export AMENT_PREFIX_PATH="$venv" CMAKE_PREFIX_PATH="$venv" PATH="$venv/bin:$PATH"
"$venv/bin/colcon" --log-base "$repo/build/msgs/log" build \
    --base-paths "$repo/msgs/tf2_msgs" --build-base "$repo/build/msgs" \
    --install-base "$venv" --merge-install \
    --cmake-args -DPython3_EXECUTABLE="$py" -DBUILD_TESTING=OFF
"$py" -c "from tf2_msgs.msg import TFMessage; print('tf2_msgs: generated,', TFMessage.__name__)"
