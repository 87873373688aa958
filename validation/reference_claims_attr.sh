#!/usr/bin/env bash
# Which mode selects in the elastic-hold cells H2-H4 of the pre-registered map of the
# reference's claims (validation/reference_claims.md): RPM3 at 140 km/h, wheel damping 0, one
# passage with the coupled-mode attribution (coupled_attribution.json) per hold, and the
# wheel-density test (wheel.density 7800 -> 9000 kg/m^3; a wheel mode's frequency scales by
# sqrt(7800/9000) = 0.931). Run after reference_claims.sh "2 3 4" (the track bases are then
# cached). Usage: bash validation/reference_claims_attr.sh [OUT]  (default
# validation/out/claims/attr). Prints one line per hold (reference_claims.py attr).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-validation/out/claims/attr}
BIN=${CORRUGATION:-target/release/corrugation}
mkdir -p "$OUT"
for h in 2:1e9 3:3e9 4:1e10; do
  n=${h%%:*}
  k=${h##*:}
  for rho in 7800 9000; do
    d=$OUT/h$n-rho$rho
    [ -s "$d.json" ] && continue
    "$BIN" passage --json --no-nodal --out "$d" --set fastening.model=RPM3 \
      --set run.speed_kmh=140 --set wheel.damping_ratio=0 --set 'fastening.hold="elastic"' \
      --set 'fastening.hold_directions=["x"]' --set "fastening.hold_stiffness=$k" \
      --set "wheel.density=$rho" > "$d.json.part"
    mv "$d.json.part" "$d.json"
  done
done
python3 validation/reference_claims.py attr "$OUT"
