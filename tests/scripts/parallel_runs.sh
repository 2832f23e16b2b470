#!/usr/bin/env bash
# Parallel runs must not break each other (issue 11, item 1): starts PARALLEL runs of SCENE at
# once, ROUNDS times, and counts the runs that fail (non-zero exit, a status other than
# "completed", or still running after LIMIT seconds), then the shared-memory files left behind.
#
#   tests/scripts/parallel_runs.sh [BIN_DIR]      # default target/release
#   ROUNDS=10 PARALLEL=8 SCENE=scenes/backbone-doubles.toml LIMIT=150 tests/scripts/parallel_runs.sh
#
# BIN_DIR holds coupler-node, fluid-node and solid-node, or the test shims it-coupler-node,
# it-fluid-node and it-solid-node. Prints one line per round and a total; exits 1 on any failure.
set -u
bin=${1:-target/release}
rounds=${ROUNDS:-10}
parallel=${PARALLEL:-8}
scene=${SCENE:-scenes/backbone-doubles.toml}
limit=${LIMIT:-150}
if [ -x "$bin/coupler-node" ]; then
    coupler="$bin/coupler-node"
elif [ -x "$bin/it-coupler-node" ]; then
    coupler="$bin/it-coupler-node"
    export COSIM_FLUID_BIN="$bin/it-fluid-node" COSIM_SOLID_BIN="$bin/it-solid-node"
else
    echo "no coupler-node or it-coupler-node in $bin" >&2
    exit 2
fi
work=$(mktemp -d "${TMPDIR:-/tmp}/cosim-parallel.XXXXXX")
total_failed=0
started=$(date +%s)
for round in $(seq 1 "$rounds"); do
    pids=()
    for k in $(seq 1 "$parallel"); do
        timeout --signal=KILL "$limit" "$coupler" run "$scene" --out "$work/$round-$k" --quiet \
            >"$work/$round-$k.log" 2>&1 &
        pids+=($!)
    done
    failed=0
    reasons=""
    for k in $(seq 1 "$parallel"); do
        wait "${pids[$((k - 1))]}"
        rc=$?
        status=$(grep -o '"status": "[^"]*"' "$work/$round-$k/summary.json" 2>/dev/null | cut -d'"' -f4)
        if [ "$rc" -ne 0 ] || [ "$status" != "completed" ]; then
            failed=$((failed + 1))
            why=$(tail -n 1 "$work/$round-$k.log")
            reasons="$reasons
    run $k: exit $rc, status '${status}': ${why}"
        fi
    done
    total_failed=$((total_failed + failed))
    echo "round $round: $failed of $parallel failed$reasons"
done
elapsed=$(($(date +%s) - started))
echo "total: $total_failed of $((rounds * parallel)) runs failed in $rounds rounds of $parallel ($elapsed s)"
leftovers=$(ls /dev/shm 2>/dev/null | grep -c '^cosim_' || true)
echo "cosim_* files in /dev/shm afterwards: $leftovers"
rm -rf "$work"
[ "$total_failed" -eq 0 ]
