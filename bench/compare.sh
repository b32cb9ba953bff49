#!/usr/bin/env bash
# Benchmark (not a test): this checkout against an earlier revision, on the N-link chains
# of bench/chain.sh (default N = 10 and 100), runs interleaved so that the machine's load
# falls on both alike. Per N it prints the median over ROUNDS runs (default 5) of
#   simulate   `mbfmu simulate chainN.xml --end 1 --step 0.01 --tol 1e-6` (wall time)
#   linearize  one linearization, 1 thread, after 0.01 s (examples/lin_bench)
# for both builds and the ratio new/old (below 1: faster now).
#
# Usage: bench/compare.sh REV [N ...]      e.g. bench/compare.sh main~5 10 100
# The earlier revision is built in a temporary worktree; BASE_TARGET=DIR reuses a
# target directory for it between runs.
set -euo pipefail
cd "$(dirname "$0")/.."

rev="${1:?usage: bench/compare.sh REV [N ...]}"
shift
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(10 100)
rounds="${ROUNDS:-5}"

tmp="$(mktemp -d)"
trap 'git worktree remove --force "$tmp/base" >/dev/null 2>&1 || true; rm -rf "$tmp"' EXIT
git worktree add --detach "$tmp/base" "$rev" >/dev/null
base_target="${BASE_TARGET:-$tmp/base-target}"
(cd "$tmp/base" && CARGO_TARGET_DIR="$base_target" cargo build --release --quiet --bin mbfmu --example lin_bench)
cargo build --release --quiet --bin mbfmu --example lin_bench
new_dir="${CARGO_TARGET_DIR:-target}/release"
old_dir="$base_target/release"

# Wall time of a command, in seconds.
wall() {
    local t0 t1
    t0=$(date +%s.%N)
    "$@" >/dev/null
    t1=$(date +%s.%N)
    awk -v a="$t0" -v b="$t1" 'BEGIN {print b - a}'
}

# One linearization's time (1 thread) from lin_bench's report.
lin_time() {
    "$1" "$2" | sed -n 's/.*linearize (check included) \([0-9.e+-]*\) s (1 thread).*/\1/p'
}

median() {
    sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'
}

printf "%6s %-10s %12s %12s %10s\n" N what "old (s)" "new (s)" "new/old"
for n in "${sizes[@]}"; do
    model="$tmp/chain$n.xml"
    bench/chain_model.sh "$n" >"$model"
    : >"$tmp/sim_old"; : >"$tmp/sim_new"; : >"$tmp/lin_old"; : >"$tmp/lin_new"
    for _ in $(seq "$rounds"); do
        wall "$old_dir/mbfmu" simulate "$model" --end 1 --step 0.01 --tol 1e-6 >>"$tmp/sim_old"
        wall "$new_dir/mbfmu" simulate "$model" --end 1 --step 0.01 --tol 1e-6 >>"$tmp/sim_new"
        lin_time "$old_dir/examples/lin_bench" "$model" >>"$tmp/lin_old"
        lin_time "$new_dir/examples/lin_bench" "$model" >>"$tmp/lin_new"
    done
    for what in sim lin; do
        old=$(median <"$tmp/${what}_old")
        new=$(median <"$tmp/${what}_new")
        label=$([ "$what" = sim ] && echo simulate || echo linearize)
        printf "%6s %-10s %12.4f %12.4f %10.3f\n" "$n" "$label" "$old" "$new" "$(awk -v a="$old" -v b="$new" 'BEGIN {print b / a}')"
    done
done
