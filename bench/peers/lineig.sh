#!/usr/bin/env bash
# Benchmark (not a test): linearization + all eigenvalues of the N-link chain of
# bench/chain_model.sh hanging at rest (default N = 10 300 1000), in one run: the whole
# `mbfmu linearize --format json` process (and `--format table`, `--modes 10`) against
# Exudyn's minimal-coordinate ObjectKinematicTree in-process (model build, then
# ComputeODE2Eigenvalues: M, K and all N eigenvalues; ComputeLinearizedSystem apart);
# medians, ratio Exudyn/mbfmu (> 1: mbfmu faster), and the relative difference of the
# lowest frequencies of the two (the check that both have the same model). See
# bench/README.md and bench/peers/lineig.py.
#
#   bench/peers/lineig.sh [N ...]
#
# Environment:
#   MBFMU_BIN=PATH   use this mbfmu instead of `cargo build --release`
#                    (${CARGO_TARGET_DIR:-target}/release/mbfmu)
#   REPEATS=3        timed runs per engine and N (the median is printed)
#   MODES=10         K of `mbfmu linearize --modes K` and of the frequency check; 0: no --modes
#   PEERS_WORK=DIR   where the models go (default bench/peers/out)
#   OPENBLAS_NUM_THREADS=1  threads of numpy's and scipy's OpenBLAS (Exudyn's eigh): 1 unless
#                    set. With 2 on this 2-core machine, any other load makes eigh up to
#                    ~90x slower (OpenBLAS's threads wait for each other: N = 300 took
#                    2.8 s instead of 0.03 s while a compiler ran)
# exudyn, numpy and scipy (Exudyn's eigenvalue routine needs it) are installed into
# bench/peers/.venv on the first run; they are bench-only dependencies.
set -euo pipefail
cd "$(dirname "$0")/../.."
here=bench/peers

sizes=()
for a in "$@"; do
    case "$a" in
        -h | --help) sed -n '2,/^set -e/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
        *) sizes+=("$a") ;;
    esac
done
[ ${#sizes[@]} -gt 0 ] || sizes=(10 300 1000)

# shellcheck source=bench/peers/setup.sh
. "$here/setup.sh"
peers_setup "exudyn, numpy, scipy" exudyn numpy scipy
echo "$(date)"
echo "mbfmu: $bin ($(git log -1 --format='%h %cd' --date=short))"

export OPENBLAS_NUM_THREADS="${OPENBLAS_NUM_THREADS:-1}"
work="${PEERS_WORK:-$here/out}"
mkdir -p "$work"
"$py" "$here/lineig.py" --mbfmu "$bin" --work "$work" --repeats "${REPEATS:-3}" --modes "${MODES:-10}" \
    "${sizes[@]}"
