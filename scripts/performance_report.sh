#!/usr/bin/env bash
# Regenerates docs/PERFORMANCE.md and its figures on this machine, with the
# Mitsuba 3 comparison (outside CI: needs `pip install mitsuba numpy` and
# Debian's libllvm19).
#
#   scripts/performance_report.sh          the default scene, then the suite
#   scripts/performance_report.sh suite    the scene suite only
#   scripts/performance_report.sh holdout  the held-out scenes only
#   scripts/performance_report.sh probe    the probe scenes only
#   scripts/performance_report.sh spheres  the scenes with more spheres only
#   scripts/performance_report.sh contact  the scenes where walls cut the
#                                          light or spheres only
#   scripts/performance_report.sh random   the rooms made at random by
#                                          scripts/random_rooms.py only
#   scripts/performance_report.sh DIR [OUT_DIR]
#                                          any other folder of scenes (new
#                                          rooms, say), into OUT_DIR
#                                          (target/bench/NAME by default)
#                                          with its report OUT_DIR/report.md
#   scripts/performance_report.sh rebuild  the six suites' sections again
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

# One suite's bench arguments, its folder, Mitsuba's folder and its report:
# the scene suite (scenes/, docs/PERFORMANCE.md) for "", else the held-out
# scenes (scenes/holdout/), the probes (scenes/probe/), the scenes with
# more spheres (scenes/spheres/), those where walls cut the light or
# spheres (scenes/contact/) or the rooms made at random (scenes/random/)
# in their own report, docs/bench/NAME.md; or any other folder of scenes,
# into OUT_DIR (the second argument) with OUT_DIR/report.md.
suite_of() {
    if [ -d "$1" ]; then
        dir=${2:-target/bench/$(basename "$1")}
        mitsuba=$dir/mitsuba report=$dir/report.md
        args=(--suite --suite-dir "$1" --width 128 --height 128 --reference-spp 8192 --out-dir "$dir")
    elif [ -z "$1" ]; then
        dir=$out mitsuba=$out/mitsuba-suite report=docs/PERFORMANCE.md
        args=(--suite --width 128 --height 128 --reference-spp 8192 --out-dir "$dir")
    else
        dir=$out/$1 mitsuba=$out/$1/mitsuba report=$out/$1.md
        args=(--suite --suite-dir "scenes/$1" --width 128 --height 128 --reference-spp 8192 --out-dir "$dir")
    fi
}

# References rendered once and cached by scene hash under the suite's
# folder, Mitsuba's four samplers, then ours.
measure_suite() {
    suite_of "$@"
    "$bin" bench convergence "${args[@]}" --reference-only
    python3 scripts/mitsuba/compare.py --suite "$dir/suite.tsv" "$mitsuba" --seeds "$seeds"
    "$bin" bench convergence "${args[@]}" --max-spp 16384 --seeds "$seeds" --mitsuba-dir "$mitsuba" --report "$report"
    agreement "$dir/suite.tsv" "$mitsuba"
}

case "${1:-all}" in
    rebuild)
        for which in "" holdout probe spheres contact random; do
            suite_of "$which"
            "$bin" bench convergence "${args[@]}" --mitsuba-dir "$mitsuba" --report "$report" --from-csv
        done
        exit 0
        ;;
    holdout | probe | spheres | contact | random)
        measure_suite "$1"
        exit 0
        ;;
    "" | all | suite) ;;
    *)
        if [ ! -d "$1" ]; then
            echo "performance_report.sh: $1: not a suite's name nor a folder of scenes" >&2
            exit 2
        fi
        mkdir -p "${2:-target/bench/$(basename "$1")}"
        measure_suite "$1" "${2:-}"
        exit 0
        ;;
esac

if [ "${1:-all}" != suite ]; then
    # 1. The reference (our CPU renderer, 100x the largest budget).
    "$bin" bench convergence --reference-only --out-dir "$out"
    # 2. Mitsuba's error against time against that reference (its fastest sampler).
    python3 scripts/mitsuba/compare.py scenes/default.toml "$out/reference.exr" "$out/mitsuba.csv" --seeds "$seeds"
    # 3. Throughput and convergence side by side, and the report.
    "$bin" bench all --seeds "$seeds" --reference "$out/reference.exr" --mitsuba-csv "$out/mitsuba.csv" --out-dir "$out" --report docs/PERFORMANCE.md
fi

# The scene suite.
measure_suite ""
