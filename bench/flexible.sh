#!/bin/sh
# Flexible-body benchmark (issue 14): simulation and linearization time for 5/20/50
# modes (the suspension example: 6/20/50) and 20 vs 200 beam elements; prints the
# 200/20 ratios (≈ 1 expected: the equations use inertia invariants, computed once per
# body).
set -e
cd "$(dirname "$0")/.."
cargo run --release --example flex_bench
