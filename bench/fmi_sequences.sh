#!/usr/bin/env bash
# Robustness run (not a test of speed): the FMI call-sequence fuzzer of
# tests/it/fmi_sequences.rs with many sequences (default 5000; CI runs 300). Each sequence
# instantiates one example model (sometimes wrongly) and makes random legal and illegal
# calls; the run fails on a crash, a panic inside an export, a call making more
# integrator step attempts than its solver.maxSteps, or a non-finite value returned with
# fmi2OK. Prints the calls made, the statuses, the wall time, the busiest call (integrator
# step attempts) and the successful calls per function.
#   bench/fmi_sequences.sh [SEQUENCES] [SEED]
set -euo pipefail
cd "$(dirname "$0")/.."
MBFMU_FMI_SEQUENCES="${1:-5000}" MBFMU_FMI_SEED="${2:-12}" \
    cargo test --release --quiet --test it fmi_sequences:: -- --nocapture
