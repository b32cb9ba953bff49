#!/usr/bin/env bash
# Benchmark (not a test): linearization of the N-link chain of bench/chain.sh for
# N = 10, 100, 1000 (or the sizes given as arguments). For each N, examples/lin_bench
# reports the times of initialization, state selection (Eq. 33, at t = 0), the partition
# check (after Eq. 36) and one linearization (Eq. 34, check included) with 1 and 2 threads
# after 0.01 s of motion, and their ratio to one integrator Newton iteration; GNU time
# adds the peak resident memory of the whole run (simulation included).
set -euo pipefail
cd "$(dirname "$0")/.."

sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(10 100 1000)

cargo build --release --quiet --example lin_bench
bin="${CARGO_TARGET_DIR:-target}/release/examples/lin_bench"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

for n in "${sizes[@]}"; do
    model="$tmp/chain$n.xml"
    bench/chain_model.sh "$n" >"$model"
    if [ -x /usr/bin/time ]; then
        /usr/bin/time -f "peak RSS %M KiB" "$bin" "$model"
    else
        "$bin" "$model"
    fi
done
