#!/usr/bin/env bash
# Benchmark (not a test): mbfmu against Exudyn and MuJoCo on the N-link spatial pendulum
# chain of bench/chain_model.sh (default N = 10 100 300), 1 s from j1 = j2 = 0.5 rad, in
# one run: wall times (medians), us per step, tip errors against a tight mbfmu reference,
# ratios engine/mbfmu (> 1: mbfmu faster); then the precision-work diagram (tip error vs
# CPU time, N = 10 and 100) into bench/peers/precision_work.png. See bench/README.md.
#
#   bench/peers/run.sh [N ...]
#   bench/peers/run.sh --no-precision-work [N ...]      (or PEERS_PRECISION_WORK=0)
#
# Environment:
#   MBFMU_BIN=PATH        use this mbfmu (libmbfmu.so beside it, or MBFMU_LIB) instead of
#                         `cargo build --release` (${CARGO_TARGET_DIR:-target}/release/mbfmu)
#   REPEATS=3             timed runs per engine and N (the median is printed)
#   EXTRA_TOLS="1e-5 1e-6"  further mbfmu tolerances (one CLI run each, for their error)
#   PW_SIZES="10 100"     sizes of the precision-work diagram
#   PW_LIMIT=60           skip a precision-work point predicted to take longer [s]
#   PEERS_WORK=DIR        models, FMUs, cached references (default bench/peers/out)
# The peers (exudyn, mujoco, fmpy, numpy, matplotlib) are installed into
# bench/peers/.venv on the first run; they are bench-only dependencies.
set -euo pipefail
cd "$(dirname "$0")/../.."
here=bench/peers

precision_work="${PEERS_PRECISION_WORK:-1}"
sizes=()
for a in "$@"; do
    case "$a" in
        --no-precision-work) precision_work=0 ;;
        -h | --help) sed -n '2,/^set -e/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
        *) sizes+=("$a") ;;
    esac
done
[ ${#sizes[@]} -gt 0 ] || sizes=(10 100 300)

# shellcheck source=bench/peers/setup.sh
. "$here/setup.sh"
peers_setup "exudyn, mujoco, fmpy, numpy, matplotlib" exudyn mujoco fmpy numpy matplotlib
"$py" - <<'PY'
import exudyn, fmpy, mujoco, numpy
print(f"peers: exudyn {exudyn.__version__}, mujoco {mujoco.__version__}, fmpy {fmpy.__version__}, numpy {numpy.__version__}")
PY
echo "mbfmu: $bin ($(git log -1 --format='%h %cd' --date=short))"

work="${PEERS_WORK:-$here/out}"
mkdir -p "$work"
work="$(cd "$work" && pwd)"
pose=$("$py" "$here/chain.py" sets)
pw_sizes=(${PW_SIZES:-10 100})
for n in $(printf '%s\n' "${sizes[@]}" "${pw_sizes[@]}" | sort -nu); do
    "$py" "$here/chain.py" model "$n" >"$work/chain$n.xml"
    "$py" "$here/chain.py" pose "$n" >"$work/chain${n}_pose.xml"
    # shellcheck disable=SC2086  # $pose is the list of --set NAME=VALUE arguments
    "$bin" pack "$work/chain$n.xml" -o "$work/chain$n.fmu" $pose >/dev/null
done

extra_tols="$(echo ${EXTRA_TOLS-1e-5 1e-6} | tr ' ' ',')"
"$py" "$here/peers.py" --mbfmu "$bin" --work "$work" --repeats "${REPEATS:-3}" \
    --extra-tols "$extra_tols" "${sizes[@]}"

if [ "$precision_work" != 0 ]; then
    "$py" "$here/precision_work.py" --mbfmu "$bin" --work "$work" --limit "${PW_LIMIT:-60}" \
        --png "$here/precision_work.png" "${pw_sizes[@]}"
fi
