#!/usr/bin/env bash
# Regenerates docs/PERFORMANCE.md and its figures on this machine, with the
# Mitsuba 3 comparison (outside CI: needs `pip install mitsuba numpy` and
# Debian's libllvm19).
#
#   scripts/performance_report.sh          the default scene, then the suite
#   scripts/performance_report.sh suite    the scene suite only
#   scripts/performance_report.sh holdout  the held-out scenes only
#   scripts/performance_report.sh probe    the probe scenes only
#   scripts/performance_report.sh rebuild  the three suites' sections again
#                                          from their runs' points, measuring
#                                          nothing (after a change to the
#                                          report's tables)
#
# SEEDS (default 5) sets the seeds of every measurement, ours and Mitsuba's.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -p pathtracer
bin=target/release/pathtracer
seeds=${SEEDS:-5}
out=docs/bench
mkdir -p "$out"

# Mitsuba's image of each scene of a suite's manifest agrees with our
# reference: a paired t test per 16x16 region (our own default on each
# scene of scenes/ is checked against it by a unit test).
agreement() {
    tail -n +2 "$1" | while IFS=$'\t' read -r name _file reference _rest; do
        echo "$name: Mitsuba against our reference"
        "$bin" compare "$2/$name.exr" --reference "$reference" --max-t 5 | tail -n 1
    done
}

if [ "${1:-all}" = rebuild ]; then
    "$bin" bench convergence --suite --width 128 --height 128 --reference-spp 8192 --out-dir "$out" \
        --seeds "$seeds" --mitsuba-dir "$out/mitsuba-suite" --report docs/PERFORMANCE.md --from-csv
    for which in holdout probe; do
        "$bin" bench convergence --suite --suite-dir "scenes/$which" --width 128 --height 128 --reference-spp 8192 \
            --out-dir "$out/$which" --seeds "$seeds" --mitsuba-dir "$out/$which/mitsuba" --report "$out/$which.md" --from-csv
    done
    exit 0
fi

if [ "${1:-all}" = holdout ] || [ "${1:-all}" = probe ]; then
    # The held-out scenes (scenes/holdout/) or the probe scenes
    # (scenes/probe/): the same measurements as the suite's, in their own
    # report, docs/bench/holdout.md or docs/bench/probe.md.
    which=$1
    hold=(--suite --suite-dir "scenes/$which" --width 128 --height 128 --reference-spp 8192 --out-dir "$out/$which")
    "$bin" bench convergence "${hold[@]}" --reference-only
    python3 scripts/mitsuba/compare.py --suite "$out/$which/suite.tsv" "$out/$which/mitsuba" --seeds "$seeds"
    "$bin" bench convergence "${hold[@]}" --max-spp 16384 --seeds "$seeds" --mitsuba-dir "$out/$which/mitsuba" --report "$out/$which.md"
    agreement "$out/$which/suite.tsv" "$out/$which/mitsuba"
    exit 0
fi

if [ "${1:-all}" != suite ]; then
    # 1. The reference (our CPU renderer, 100x the largest budget).
    "$bin" bench convergence --reference-only --out-dir "$out"
    # 2. Mitsuba's error against time against that reference (its fastest sampler).
    python3 scripts/mitsuba/compare.py scenes/default.toml "$out/reference.exr" "$out/mitsuba.csv" --seeds "$seeds"
    # 3. Throughput and convergence side by side, and the report.
    "$bin" bench all --seeds "$seeds" --reference "$out/reference.exr" --mitsuba-csv "$out/mitsuba.csv" --out-dir "$out" --report docs/PERFORMANCE.md
fi

# The scene suite (scenes/): references rendered once and cached by scene
# hash under docs/bench/references, Mitsuba's four samplers, then ours.
suite=(--suite --width 128 --height 128 --reference-spp 8192 --out-dir "$out")
"$bin" bench convergence "${suite[@]}" --reference-only
python3 scripts/mitsuba/compare.py --suite "$out/suite.tsv" "$out/mitsuba-suite" --seeds "$seeds"
"$bin" bench convergence "${suite[@]}" --max-spp 16384 --seeds "$seeds" --mitsuba-dir "$out/mitsuba-suite" --report docs/PERFORMANCE.md
agreement "$out/suite.tsv" "$out/mitsuba-suite"
