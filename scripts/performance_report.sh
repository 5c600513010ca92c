#!/usr/bin/env bash
# Regenerates docs/PERFORMANCE.md and its figures on this machine, with the
# Mitsuba 3 comparison (outside CI: needs `pip install mitsuba numpy` and
# Debian's libllvm19).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -p pathtracer
bin=target/release/pathtracer
out=docs/bench
mkdir -p "$out"
# 1. The reference (our CPU renderer, 100x the largest budget).
"$bin" bench convergence --reference-only --out-dir "$out"
# 2. Mitsuba's error against time against that reference.
python3 scripts/mitsuba/compare.py scenes/default.toml "$out/reference.exr" "$out/mitsuba.csv" --seeds 5
# 3. Throughput and convergence side by side, and the report.
"$bin" bench all --seeds 5 --reference "$out/reference.exr" --mitsuba-csv "$out/mitsuba.csv" --out-dir "$out" --report docs/PERFORMANCE.md
