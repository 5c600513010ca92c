#!/usr/bin/env bash
# Submits the render array, then the merge with a dependency on all of it.
set -euo pipefail
cd "$(dirname "$0")"
mkdir -p parts
render=$(sbatch --parsable render.sbatch)
sbatch --dependency=afterok:"$render" merge.sbatch
