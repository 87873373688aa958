#!/usr/bin/env bash
# The pre-registered map of the reference study's claims (validation/reference_claims.md).
# Usage: bash validation/reference_claims.sh [OUT] [HOLDS]   (default OUT validation/out/claims,
# HOLDS "0 1 2 3 4 5"). Each hold's study is resumable (finished cases are reused).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-validation/out/claims}
HOLDS=${2:-"0 1 2 3 4 5"}
BIN=${CORRUGATION:-target/release/corrugation}
mkdir -p "$OUT"
for h in $HOLDS; do
  start=$(date +%s)
  "$BIN" study "models/studies/reference-claims-h$h.toml" --out "$OUT/h$h"
  echo "hold H$h: $(( $(date +%s) - start )) s" | tee -a "$OUT/times.txt"
done
python3 validation/reference_claims.py table "$OUT" | tee "$OUT/table.md"
