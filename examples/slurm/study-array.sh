#!/usr/bin/env bash
# A design study as a Slurm job array: task I of N runs every N-th case from the I-th
# (`study --shard I/N`) into one shared output directory; a dependent job runs the study once
# more there, which reuses every finished case and writes the table, the plots and the report
# (the same files as one unsharded run).
#
#   STUDY=studies/pads.toml sbatch --array=0-7 examples/slurm/study-array.sh
#
# OUT and CACHE must be on a file system every node sees. Cases that failed are rerun by the
# final step (a rerun resumes), so a task lost to a node failure costs only its own cases.
#
#SBATCH --job-name=corrugation-study
#SBATCH --array=0-3
#SBATCH --cpus-per-task=2
#SBATCH --mem=12G
#SBATCH --time=02:00:00
#SBATCH --output=corrugation-study-%A_%a.log
set -euo pipefail

BIN=${BIN:-corrugation}
STUDY=${STUDY:?set STUDY to the study file (TOML)}
SHARDS=${SHARDS:-${SLURM_ARRAY_TASK_COUNT:-4}}
OUT=${OUT:-corrugation-out/study-${SLURM_ARRAY_JOB_ID:-local}}
CACHE=${CACHE:-$HOME/.cache/corrugation}
I=${SLURM_ARRAY_TASK_ID:-0}

"$BIN" study "$STUDY" --shard "$I/$SHARDS" --cache "$CACHE" --out "$OUT"

if [[ "$I" == 0 && -n "${SLURM_ARRAY_JOB_ID:-}" ]]; then
  sbatch --dependency="afterany:${SLURM_ARRAY_JOB_ID}" --job-name=corrugation-study-report \
    --cpus-per-task=2 --mem=12G --time=02:00:00 --output="corrugation-study-report-%j.log" \
    --wrap="$BIN study $STUDY --cache $CACHE --out $OUT"
fi
