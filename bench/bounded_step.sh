#!/usr/bin/env bash
# Benchmark (not a test): how long the step limit and the step-size collapse take to end
# a communication step that cannot finish — the speed the tests no longer time
# (tests/it/bounded_step.rs and tests/python/test_fmu_bounded_step.py count the attempts
# instead). Each case runs `mbfmu simulate --stats` and prints the integrator's counts,
# the wall time and the step attempts per second:
#   runaway   cart_pendulum_pid with its reference r ramped at 1 rad/s, one communication
#             step of 1e6 s: stopped by the step limit (MAX_STEPS, default 10000, the
#             FMU's solver.maxSteps default);
#   bicycle   the benchmark bicycle, one step of 1e6 s: the step limit on the most
#             expensive example (README: "stops a runaway step within about 10 s");
#   toggle    tests/models/fourbar_toggle.xml driven into its toggle at t* = 2.0063 s:
#             the step size collapses.
#   bench/bounded_step.sh [MAX_STEPS]
set -euo pipefail
cd "$(dirname "$0")/.."

max_steps="${1:-10000}"
cargo build --release --quiet
bin="${CARGO_TARGET_DIR:-target}/release/mbfmu"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
printf 'time,r\n0,0\n1e6,1e6\n' >"$tmp/ramp.csv"

# run NAME ARGS...: simulate with --stats (the run is expected to fail), print the counts
# and the attempts per second.
run() {
    local name="$1"
    shift
    "$bin" simulate "$@" --stats --out /dev/null 2>"$tmp/stderr" || true
    echo "== $name: $*"
    grep -v '^error' "$tmp/stderr" | sed 's/^/   /'
    grep '^error' "$tmp/stderr" | cut -c1-160 | sed 's/^/   /'
    awk '/steps attempted:/ { n = $3 } /^wall time:/ { w = $3 }
         END { if (w > 0) printf "   %.0f step attempts per second\n", n / w }' "$tmp/stderr"
}

run runaway models/cart_pendulum_pid.xml --input "$tmp/ramp.csv" --end 1e6 --step 1e6 --max-steps "$max_steps"
run bicycle models/benchmark_bicycle.xml --end 1e6 --step 1e6 --max-steps "$max_steps"
run toggle tests/models/fourbar_toggle.xml --end 2.2 --step 0.1 --max-steps "$max_steps"
