#!/usr/bin/env bash
# `make test` in fresh clones of HEAD beside the load of issue 37's acceptance: two busy loops
# and a second stack (rns_demo --no-record --real-time-factor 0, looped on domain 57).
#
#   scripts/loaded_make_test.sh [RUNS]      (default 3; needs `make venv` for the second stack)
#
# Each run clones HEAD into a temporary folder and runs .ci/run there (it installs its own
# .venv), on ROS_DOMAIN_ID 72..79 (the tests use 8 domains from there). One line per run: exit
# code, wall time, load average, the pytest summary; logs stay in the printed folder. Every run
# is made (a failed one does not stop the rest). The load's process groups are ended on exit.
set -u
runs="${1:-3}"
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
demo="$repo/.venv/bin/rns_demo"
[ -x "$demo" ] || { echo "loaded_make_test: $demo missing: run make venv first" >&2; exit 2; }
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST RMW_IMPLEMENTATION=rmw_fastrtps_cpp
work="$(mktemp -d /tmp/loaded_make_test.XXXXXX)"
groups=()
stop_load() {
    for group in "${groups[@]}"; do kill -- "-$group" 2>/dev/null; done
}
trap stop_load EXIT
trap 'exit 130' INT TERM
for _ in 1 2; do
    setsid timeout 10000 sh -c 'while :; do :; done' &
    groups+=("$!")
done
# the second stack runs this checkout's code (PYTHONPATH): a worktree may share another
# checkout's editable .venv
PYTHONPATH="$repo" ROS_DOMAIN_ID=57 setsid timeout 10000 sh -c \
    "while :; do '$demo' --no-record --real-time-factor 0 --domain-id 57 >/dev/null 2>&1; sleep 0.2; done" &
groups+=("$!")
failed=0
for run in $(seq 1 "$runs"); do
    clone="$work/run$run"
    git clone -q "$repo" "$clone"
    start=$(date +%s)
    (cd "$clone" && ROS_DOMAIN_ID=72 CI=true bash .ci/run >"$clone.log" 2>&1)
    rc=$?
    [ $rc -eq 0 ] || failed=$((failed + 1))
    echo "run $run at $(git -C "$clone" rev-parse --short HEAD): exit $rc after" \
        "$(($(date +%s) - start)) s, load $(cut -d' ' -f1 /proc/loadavg):" \
        "$(grep -E '^(=+ )?[0-9]+ (passed|failed)|(passed|failed).* in [0-9.]+s' "$clone.log" | tail -1)"
done
echo "loaded_make_test: $failed of $runs runs failed; logs in $work"
[ $failed -eq 0 ]
