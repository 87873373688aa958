#!/usr/bin/env bash
# A speed sweep as a Slurm job array: task I of N runs shard I/N of the speeds into its own
# directory; a dependent job joins the shards with `corrugation merge` (the same files as one
# unsharded sweep, bit for bit).
#
#   sbatch examples/slurm/sweep-array.sh                 # 4 shards of 54.8–219 km/h, step 1
#   MODEL=models/my-track.toml SHARDS=8 sbatch --array=0-7 examples/slurm/sweep-array.sh
#
# The job submits its own merge step (afterok on the whole array) from task 0. Every task
# needs the same modal cache: set CACHE to a shared directory. The first task to need a
# basis computes it; run `corrugation modes --model "$MODEL" --cache "$CACHE"` once before
# submitting so that the tasks only load it (minutes saved per task on the default model).
#
#SBATCH --job-name=corrugation-sweep
#SBATCH --array=0-3
#SBATCH --cpus-per-task=2
#SBATCH --mem=8G
#SBATCH --time=01:00:00
#SBATCH --output=corrugation-sweep-%A_%a.log
set -euo pipefail

BIN=${BIN:-corrugation}                 # the binary (cargo build --release: target/release/corrugation)
MODEL=${MODEL:-}                        # a model file; empty = the embedded default model
SETS=${SETS:-}                          # overrides, e.g. "run.fmax=3000 track.bays=10"
SPEEDS=${SPEEDS:-54.8:219:1}            # km/h, START:STOP:STEP or a list
SHARDS=${SHARDS:-${SLURM_ARRAY_TASK_COUNT:-4}}
OUT=${OUT:-corrugation-out/sweep-${SLURM_ARRAY_JOB_ID:-local}}
CACHE=${CACHE:-$HOME/.cache/corrugation}
I=${SLURM_ARRAY_TASK_ID:-0}

model_args=()
[[ -n "$MODEL" ]] && model_args=(--model "$MODEL")
for s in $SETS; do model_args+=(--set "$s"); done

"$BIN" sweep "${model_args[@]}" --speeds "$SPEEDS" --shard "$I/$SHARDS" \
  --cache "$CACHE" --out "$OUT/shard-$I"

if [[ "$I" == 0 && -n "${SLURM_ARRAY_JOB_ID:-}" ]]; then
  shards=()
  for ((k = 0; k < SHARDS; k++)); do shards+=("$OUT/shard-$k"); done
  sbatch --dependency="afterok:${SLURM_ARRAY_JOB_ID}" --job-name=corrugation-merge \
    --cpus-per-task=1 --mem=2G --time=00:10:00 --output="corrugation-merge-%j.log" \
    --wrap="$BIN merge ${shards[*]} --out $OUT/merged"
fi
