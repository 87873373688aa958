#!/usr/bin/env bash
# The excitation cells E1 (start from rest) and E2 (weak broadband roughness) of the
# pre-registered map of the reference study's claims (validation/reference_claims.md), hold
# H0 (the presets' rigid strips) or, with HOLD=1..4, an elastic hold. E0 (static start) is run
# by reference_claims.sh (which extracts the bases these passages load from the cache).
# Usage: bash validation/reference_claims_e.sh [OUT] [EXCITATIONS]
#   (default OUT validation/out/claims, EXCITATIONS "1 2"; ZETAS="0" runs only the undamped
#   wheel). Finished passages are reused.
# Cells: RPM1-RPM5 x wheel damping 0, 1e-3 x 130, 140, 150 km/h; E2 for roughness seeds
# 1, 2, 3 (profiles by `reference_claims.py roughness`). Each passage is one
# `corrugation passage --json` (about 20 s wall on the default model once its modes are
# cached; the five H0 bases are extracted by reference_claims.sh "0").
# Then `python3 validation/reference_claims.py etable OUT` prints the table.
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-validation/out/claims}
EXC=${2:-"1 2"}
# ZETAS: the wheel damping ratios to run (default both registered values).
ZETAS=${ZETAS:-"0 0.001"}
# HOLD: the longitudinal hold of the cells (registered factor H): 0 the presets' rigid strips
# (default); 1-4 elastic x-holds of 3e8, 1e9, 3e9, 1e10 N/m per fastening.
HOLD=${HOLD:-0}
case "$HOLD" in
  0) hold=() ;;
  1 | 2 | 3 | 4)
    k=$(echo "3e8 1e9 3e9 1e10" | cut -d' ' -f"$HOLD")
    hold=(--set 'fastening.hold="elastic"' --set 'fastening.hold_directions=["x"]'
      --set "fastening.hold_stiffness=$k")
    ;;
  *) echo "HOLD must be 0-4 (H5 has no E cells), got $HOLD" >&2; exit 2 ;;
esac
BIN=${CORRUGATION:-target/release/corrugation}
mkdir -p "$OUT"
run() { # run DEST.json ARGS...: one passage, skipped when its JSON exists
  local dest=$1
  shift
  [ -s "$dest" ] && return 0
  "$BIN" passage --json --no-coupled --no-nodal --out "${dest%.json}" "$@" > "$dest.part"
  mv "$dest.part" "$dest"
}
for e in $EXC; do
  start=$(date +%s)
  mkdir -p "$OUT/e$e"
  if [ "$e" = 2 ]; then
    python3 validation/reference_claims.py roughness "$OUT/e2"
  fi
  # E2's seeds outermost, so that an interrupted run has whole seeds (all five models).
  seeds="-"
  [ "$e" = 2 ] && seeds="1 2 3"
  for s in $seeds; do
    for rpm in RPM1 RPM2 RPM3 RPM4 RPM5; do
      for z in $ZETAS; do
        for v in 130 140 150; do
          sets=(--set "fastening.model=$rpm" --set "wheel.damping_ratio=$z" --set "run.speed_kmh=$v"
            ${hold[@]+"${hold[@]}"})
          if [ "$e" = 1 ]; then
            run "$OUT/e1/$rpm-z$z-v$v.json" "${sets[@]}" --set 'run.start="rest"'
          else
            run "$OUT/e2/$rpm-z$z-v$v-s$s.json" "${sets[@]}" --corrugation "$OUT/e2/roughness-seed$s.csv"
          fi
        done
      done
    done
  done
  echo "excitation E$e: $(( $(date +%s) - start )) s" | tee -a "$OUT/times.txt"
done
python3 validation/reference_claims.py etable "$OUT" | tee "$OUT/etable.md"
