#!/usr/bin/env bash
# The explicit FE path against the reduced model (validation/explicit.md). Run from the
# repo root; each case is about 10 minutes on 2 cores (one explicit passage) plus the
# reduced passages (seconds, once the modal bases are cached).
#   bash validation/explicit.sh            # every case
#   bash validation/explicit.sh rpm3-140   # one case: rpm3-140 rpm1-140 rpm4-140 rpm5-140 rpm3-98
#                                          #   rpm3-118 rpm3-heavy-wheel rpm3-trial10
#                                          # growth: rpm3-grow (the trial-amplitude procedure
#                                          #   on both engines, five explicit passages)
#                                          # convergence checks: rpm3-140-dtc-half (half the
#                                          #   contact step), rpm3-140-node (node-line load)
# GRID sets the contact grid of every engine of every case: by default the grid at which the
# explicit path's frequency selection is converged (grid_nx 128 and 64 agree within 0.7 %,
# validation/explicit.md); GRID="" runs the model's own grid (grid_nx 32: the explicit path
# warns, its 16 us contact step selects a spurious frequency). A case's own --set comes after
# GRID and wins (rpm3-140-dtc-half). EXTRA adds more --set pairs to every engine, e.g.
#   EXTRA="--set track.ends=\"absorbing\"" OUT=validation/out/explicit-absorbing \
#     bash validation/explicit.sh rpm1-140
# Outputs: validation/out/explicit/CASE/{explicit,reduced,reduced-consistent}/ and
# CASE/table.md (explicit_compare's side-by-side table, the misses listed under it).
set -euo pipefail
cd "$(dirname "$0")/.."
# PROFILE=dev uses the dev profile (with CARGO_PROFILE_DEV_OPT_LEVEL=3: optimised, no LTO,
# a much shorter build); default release.
PROFILE=${PROFILE:-release}
DIR=$PROFILE
[ "$PROFILE" = dev ] && DIR=debug
# SKIP_CONSISTENT=1 leaves out the reduced passage with the position-dependent residual
# flexibility (about 5 minutes of CPU at contact.grid_nx 128).
# BIN and CMP may name copies of the binaries (so that a rebuild cannot swap them mid-run);
# when both are given nothing is built.
if [ -z "${BIN:-}" ] || [ -z "${CMP:-}" ]; then
  cargo build --profile "$PROFILE" --quiet --bin corrugation --example explicit_compare
fi
BIN=${BIN:-target/$DIR/corrugation}
CMP=${CMP:-target/$DIR/examples/explicit_compare}
OUT=${OUT:-validation/out/explicit}

case_sets() {
  case "$1" in
    rpm3-140) echo "--set fastening.model=RPM3 --set run.speed_kmh=140" ;;
    rpm3-140-dtc-half) echo "--set fastening.model=RPM3 --set run.speed_kmh=140 --set contact.grid_nx=64" ;;
    rpm3-140-node) echo "--set fastening.model=RPM3 --set run.speed_kmh=140 --set explicit.load_spread=\"node\"" ;;
    rpm1-140) echo "--set fastening.model=RPM1 --set run.speed_kmh=140" ;;
    rpm4-140) echo "--set fastening.model=RPM4 --set run.speed_kmh=140" ;;
    rpm5-140) echo "--set fastening.model=RPM5 --set run.speed_kmh=140" ;;
    rpm3-98) echo "--set fastening.model=RPM3 --set run.speed_kmh=98" ;;
    rpm3-118) echo "--set fastening.model=RPM3 --set run.speed_kmh=118" ;;
    rpm3-heavy-wheel) echo "--set fastening.model=RPM3 --set run.speed_kmh=140 --set wheel.density=9000" ;;
    rpm3-trial10) echo "--set fastening.model=RPM3 --set run.speed_kmh=140" ;;
    rpm3-grow) echo "--set fastening.model=RPM3 --set run.speed_kmh=140" ;;
    *) echo "unknown case $1" >&2; exit 2 ;;
  esac
}

run_case() {
  local c=$1 dir=$OUT/$1 sets prof=()
  sets="${GRID-"--set contact.grid_nx=128 --set contact.grid_ny=16"} $(case_sets "$c") ${EXTRA:-}"
  mkdir -p "$dir"
  if [ "$c" = rpm3-grow ]; then
    # The whole trial-amplitude procedure on each engine (default amplitudes 10-160 µm).
    # shellcheck disable=SC2086
    # AMPS (default the registered 10,40,80,160; the run recorded used 10,40,80, see the page).
    /usr/bin/time -v $BIN grow --engine explicit $sets --amplitudes-um "${AMPS:-10,40,80,160}" --no-rate --json --out "$dir/explicit" \
      > "$dir/explicit.json" 2> "$dir/explicit.time"
    # shellcheck disable=SC2086
    /usr/bin/time -v $BIN grow $sets --amplitudes-um "${AMPS:-10,40,80,160}" --no-rate --json --out "$dir/reduced" \
      > "$dir/reduced.json" 2> "$dir/reduced.time"
    python3 validation/explicit_grow.py "$dir" | tee "$dir/table.md"
    return
  fi
  if [ "$c" = rpm3-trial10 ]; then
    # The reduced model's 10 µm trial corrugation: −c·W_band of its smooth passage.
    # shellcheck disable=SC2086
    $BIN grow $sets --amplitudes-um 10 --out "$dir/grow" > /dev/null
    awk -F, 'NR == 1 { print "x_m,height_um"; next } { printf "%s,%.9g\n", $1, 10 * $3 }' \
      "$dir/grow/trial_shape.csv" > "$dir/trial10.csv"
    prof=(--corrugation "$dir/trial10.csv")
  fi
  # shellcheck disable=SC2086
  /usr/bin/time -v $BIN passage $sets "${prof[@]}" --no-nodal --out "$dir/reduced" --json > "$dir/reduced.json" 2> "$dir/reduced.time"
  local consistent=()
  if [ -z "${SKIP_CONSISTENT:-}" ]; then
    # shellcheck disable=SC2086
    /usr/bin/time -v $BIN passage $sets "${prof[@]}" --no-nodal --set run.residual_variation='"consistent"' \
      --out "$dir/reduced-consistent" --json > "$dir/reduced-consistent.json" 2> "$dir/reduced-consistent.time"
    consistent=("$dir/reduced-consistent")
  fi
  # shellcheck disable=SC2086
  /usr/bin/time -v $BIN explicit $sets "${prof[@]}" --out "$dir/explicit" --json > "$dir/explicit.json" 2> "$dir/explicit.time"
  $CMP "$dir/explicit" "$dir/reduced" "${consistent[@]}" | tee "$dir/table.md"
}

if [ $# -eq 0 ]; then
  set -- rpm3-140 rpm1-140 rpm4-140 rpm3-98 rpm3-118 rpm3-heavy-wheel rpm3-trial10
fi
for c in "$@"; do
  echo "== $c"
  run_case "$c"
done
