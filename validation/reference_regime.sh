#!/usr/bin/env bash
# Runs of validation/reference_regime.md.
#   bash validation/reference_regime.sh reflection   # part A1-A3: the ends' energy reflection (~15 min on 2 cores)
#   bash validation/reference_regime.sh a5 [CACHE]   # part A5: free vs absorbing ends on the default and the soft-hold preset
# Outputs in validation/out/reference_regime/ (summaries; the passages' full outputs in $OUT).
set -euo pipefail
cd "$(dirname "$0")/.."
OUTDIR=validation/out/reference_regime
mkdir -p "$OUTDIR"
case "${1:-}" in
  reflection)
    cargo run --release --example end_reflection | tee "$OUTDIR/end_reflection.txt"
    ;;
  a5)
    CACHE=${2:-${XDG_CACHE_HOME:-$HOME/.cache}/corrugation}
    OUT=${OUT:-/tmp/corrugation-a5}
    cargo build --release --bin corrugation
    BIN=target/release/corrugation
    for model in default reference-rpm3; do
      for ends in free absorbing; do
        M=(); [ "$model" = default ] || M=(--model "models/$model.toml")
        "$BIN" passage "${M[@]}" --set track.ends=$ends --cache "$CACHE" --out "$OUT/$model-$ends" \
          --json --no-coupled > "$OUT/$model-$ends.json"
      done
    done
    python3 validation/reference_regime_summary.py "$OUT" | tee "$OUTDIR/a5_summary.txt"
    ;;
  *)
    echo "usage: $0 reflection | a5 [CACHE]" >&2; exit 2 ;;
esac
