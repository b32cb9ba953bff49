#!/usr/bin/env bash
# Benchmark (not a test): eigenvalues of the N-link chain of bench/chain.sh hanging at
# rest (bench/chain_model.sh N hanging), whole process, peak RSS by GNU time:
#   full   `mbfmu linearize` (dense A of Eq. 36, all 2N eigenvalues; the second-order
#          route λ² = eig(X)) for N ≤ 3000,
#   modes  `mbfmu linearize --modes 10` (shift-invert Arnoldi on the sparse pencil),
# and their ratio. Sizes: the arguments, else 300 1000 3000 10000.
set -euo pipefail
cd "$(dirname "$0")/.."

sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(300 1000 3000 10000)
cargo build --release --quiet
bin="${CARGO_TARGET_DIR:-target}/release/mbfmu"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

timed() { # prints "seconds KiB"
    /usr/bin/time -f "%e %M" -o "$tmp/time" "$@" >"$tmp/out" 2>"$tmp/err" || { cat "$tmp/err" >&2; return 1; }
    cat "$tmp/time"
}

printf "%7s %12s %12s %12s %12s %8s  %s\n" N "full [s]" "full [MiB]" "modes [s]" "modes [MiB]" ratio "modes: solves, restarts"
for n in "${sizes[@]}"; do
    model="$tmp/hang$n.xml"
    bench/chain_model.sh "$n" hanging >"$model"
    full_s="-" full_m="-" ratio="-"
    if [ "$n" -le 3000 ]; then
        read -r full_s full_k < <(timed "$bin" linearize "$model")
        full_m=$((full_k / 1024))
    fi
    read -r modes_s modes_k < <(timed "$bin" linearize "$model" --modes 10)
    info=$(grep -o "[0-9]* solves, [0-9]* restarts" "$tmp/out" || true)
    [ "$full_s" = "-" ] || ratio=$(awk -v a="$full_s" -v b="$modes_s" 'BEGIN { printf "%.1f", a / b }')
    printf "%7s %12s %12s %12s %12s %8s  %s\n" "$n" "$full_s" "$full_m" "$modes_s" $((modes_k / 1024)) "$ratio" "$info"
done
