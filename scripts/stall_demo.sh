#!/usr/bin/env bash
# A node of rns_demo that gets no core for a while, on purpose: the demo runs the short 30 deg
# roll (test/rns_testing.py SHORT_ROLL_SCENARIO) on the wall clock in dynamic mode, and AFTER
# seconds after NODE's process appears it is stopped (SIGSTOP) for STALL seconds, then continued.
# Prints the demo's table row; its log and recordings are in the output folder.
#
#   scripts/stall_demo.sh NODE AFTER STALL [OUT] [extra rns_demo options...]
#   scripts/stall_demo.sh rns_controller 5.0 0.07      # a stall the reference rides over
#   scripts/stall_demo.sh rns_operator 4.4 0.5         # the operator's stream falls short
#
# AFTER counts from the process's start: on a quiet 2-core machine the roll runs from about
# 4.3 s to 7.3 s after rns_controller appears; on a busy one it starts later.
# STALL_DEMO_ROS_ARGS adds --ros-args for every node (e.g. "-p state_hold_age:=0.5").
# Loopback only, on its own ROS domain (91 unless ROS_DOMAIN_ID is set).
set -euo pipefail
if [ $# -lt 3 ]; then
    echo "usage: $0 NODE AFTER STALL [OUT] [rns_demo options...]" >&2
    exit 2
fi
node=$1 after=$2 stall=$3 out=${4:-$(mktemp -d /tmp/stall_demo.XXXX)}
shift $(( $# >= 4 ? 4 : 3 ))
repo=$(cd "$(dirname "$0")/.." && pwd)
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST ROS_DOMAIN_ID=${ROS_DOMAIN_ID:-91}
mkdir -p "$out"
"$repo/.venv/bin/python" - "$out/short.yaml" "$repo/test" <<'PY'
import sys

import yaml

sys.path.insert(0, sys.argv[2])
from rns_testing import SHORT_ROLL_SCENARIO

with open(sys.argv[1], "w") as stream:
    yaml.safe_dump(SHORT_ROLL_SCENARIO, stream)
PY
"$repo/.venv/bin/rns_demo" --scenario "$out/short.yaml" --summary "$out/summary.json" \
    --domain-id "$ROS_DOMAIN_ID" --output "$out" --mode dynamic --methods dls --wall-clock "$@" \
    --ros-args -p state_timeout:=0.5 ${STALL_DEMO_ROS_ARGS:-} > "$out/demo.log" 2>&1 &
demo=$!
pid=
for _ in $(seq 300); do
    pid=$(pgrep -f "/$node --ros-args" | head -n 1 || true)
    [ -n "$pid" ] && break
    sleep 0.1
done
if [ -z "$pid" ]; then
    echo "$node never started (see $out/demo.log)" >&2
    kill "$demo" 2>/dev/null || true
    exit 2
fi
sleep "$after"
kill -STOP "$pid" && sleep "$stall" && kill -CONT "$pid"
wait "$demo" || true
grep -A2 "^method" "$out/demo.log" | tail -n 1 | cut -c1-90
grep -h "between two ticks\|waited\|note:" "$out/demo.log" || true
echo "log, summary and recordings: $out"
