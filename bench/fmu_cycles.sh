#!/usr/bin/env bash
# Benchmark (not a test of speed): the FMU instance cycles of tests/memory_alloc.rs —
# 10 000 fmi2Instantiate/fmi2FreeInstance cycles of the pendulum, and 1000 that also
# initialize and leave an FMU state for fmi2FreeInstance to free — with their wall time
# per cycle (the test bounds only what it counts: live bytes, allocations per cycle).
# Prints, per run, the cycles, the seconds, µs per cycle, the growth of the live bytes
# and the allocations and bytes allocated per cycle.
#   bench/fmu_cycles.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cargo test --release --quiet --test memory_alloc -- --nocapture --test-threads=1 2>&1 |
    grep -E 'cycles in|serializes to|test result'
