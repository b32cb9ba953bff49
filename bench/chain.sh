#!/usr/bin/env bash
# Benchmark (not a test): an N-link spatial pendulum chain for N = 10, 100, 1000
# (or the sizes given as arguments: bench/chain.sh 10 50).
#
# Link k (mass 0.1 kg, length 0.1 m, inertia m L^2/12 about every axis) hangs from the
# tip of link k-1 (link 1 from the ground origin) by a revolute joint whose axis is ground
# x for odd k and ground y for even k. Every body starts with identity orientation and
# the links point in tilted, varying directions, so the start is exactly consistent and
# the motion is spatial; gravity -z. Each model is simulated for 1 s at tolerance 1e-6
# (`mbfmu simulate --end 1 --step 0.01 --tol 1e-6`); the table gives N, the wall time
# and the peak resident memory of the mbfmu process (GNU time; else Python getrusage).
# BENCH_TIMEOUT=SECONDS stops a run that takes longer (reported as exit 124).
set -euo pipefail
cd "$(dirname "$0")/.."

sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(10 100 1000)

cargo build --release --quiet
bin="${CARGO_TARGET_DIR:-target}/release/mbfmu"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

# chain_model N: the N-link chain model, on stdout.
chain_model() { bench/chain_model.sh "$1"; }

# measure CMD...: run CMD, print "wall_seconds peak_rss_kib status" (status 0 = success).
measure() {
    local stats="$tmp/stats" status=0
    if [ -x /usr/bin/time ]; then
        /usr/bin/time -f "%e %M" -o "$stats" "$@" >/dev/null 2>"$tmp/stderr" || status=$?
        echo "$(tail -n 1 "$stats") $status"
    else
        # No GNU time: wall clock from Python, peak RSS from getrusage(RUSAGE_CHILDREN).
        python3 - "$@" 2>"$tmp/stderr" <<'PY' || true
import resource, subprocess, sys, time
t = time.perf_counter()
status = subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL).returncode
wall = time.perf_counter() - t
print(f"{wall:.2f} {resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss} {status}")
PY
    fi
}

printf "%6s  %10s  %14s  %s\n" "N" "wall [s]" "peak RSS [MiB]" "status"
for n in "${sizes[@]}"; do
    model="$tmp/chain$n.xml"
    chain_model "$n" >"$model"
    limit=()
    [ -z "${BENCH_TIMEOUT:-}" ] || limit=(timeout "$BENCH_TIMEOUT")
    read -r wall rss status < <(measure "${limit[@]}" "$bin" simulate "$model" --end 1 --step 0.01 --tol 1e-6)
    if [ "$status" = 0 ]; then
        note="ok"
    elif [ "$status" = 124 ] && [ -n "${BENCH_TIMEOUT:-}" ]; then
        note="stopped after BENCH_TIMEOUT=${BENCH_TIMEOUT} s"
    else
        note="failed (exit $status): $(head -n 1 "$tmp/stderr")"
    fi
    printf "%6d  %10.2f  %14.1f  %s\n" "$n" "$wall" "$(awk -v k="$rss" 'BEGIN { print k / 1024 }')" "$note"
done
