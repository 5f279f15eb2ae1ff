#!/usr/bin/env bash
# Example Slurm job array for the benchmark experiments: N shards of the plan run as array
# tasks 1..N, then one dependent job merges them. Adapt partition, time and paths; the
# build directory must be on a file system every node sees, and so must experiments/.
#
#   sbatch --array=1-16 experiments/slurm_array.sh             # the shards
#   sbatch --dependency=afterany:<array job id> \
#          --wrap "build/experiments/run_experiments merge"    # the tables and plots
#
# Each task runs the cases and jobs i, i+N, i+2N, ... of the plan (round-robin; a job whose
# case another task has not generated yet generates it itself, in a private directory that
# is renamed into place, so tasks never see half a case). A task writes one small JSON per
# finished job to experiments/results/jobs/, so a rerun of a failed task skips what is done.
#SBATCH --job-name=chordfit-bench
#SBATCH --cpus-per-task=2
#SBATCH --time=08:00:00
#SBATCH --mem=2G
#SBATCH --output=slurm-%A_%a.out
set -euo pipefail
cd "${SLURM_SUBMIT_DIR:-$(dirname "${BASH_SOURCE[0]}")/..}"
build="${CHORDFIT_BUILD:-build}"
"$build/experiments/run_experiments" run --shard "${SLURM_ARRAY_TASK_ID}/${SLURM_ARRAY_TASK_COUNT}"
