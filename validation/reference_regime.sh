#!/usr/bin/env bash
# Runs of validation/reference_regime.md.
#   bash validation/reference_regime.sh reflection   # part A1-A3: the ends' energy reflection (~15 min on 2 cores)
#   bash validation/reference_regime.sh a5 [CACHE]   # part A5: free vs absorbing ends on the default and the soft-hold preset
#   bash validation/reference_regime.sh d [CACHE]    # part D: the claims cells with the wheels W1, W2 (~30 passages, 16 bays)
#   bash validation/reference_regime.sh e [CACHE]    # part E: the reference-described presets (~2 h, 9-11 GB, one at a time)
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
  d)
    CACHE=${2:-${XDG_CACHE_HOME:-$HOME/.cache}/corrugation}
    OUT=${OUT:-/tmp/corrugation-d}
    cargo build --release --bin corrugation
    BIN=target/release/corrugation
    W1=(--set wheel.web_offset=-0.0025 --set wheel.web_thickness=0.1)
    W2=("${W1[@]}" --set wheel.brake_disc=false)
    mkdir -p "$OUT"
    for w in W1 W2; do
      if [ $w = W1 ]; then W=("${W1[@]}"); else W=("${W2[@]}"); fi
      for r in 3 1 2 4 5; do for v in 130 140 150; do
        "$BIN" passage --model models/dutch-rpm$r.toml "${W[@]}" --set run.speed_kmh=$v --cache "$CACHE" \
          --no-coupled --no-nodal --json --out "$OUT/$w-rpm$r-$v" > "$OUT/$w-rpm$r-$v.json"
      done; done
    done
    "$BIN" coupled-modes --cache "$CACHE" "${W1[@]}" --list-to-hz 1600 --out "$OUT/cm-w1" > "$OUT/cm-w1.txt"
    "$BIN" coupled-modes --cache "$CACHE" --list-to-hz 1600 --out "$OUT/cm-default" > "$OUT/cm-default.txt"
    ;;
  e)
    CACHE=${2:-${XDG_CACHE_HOME:-$HOME/.cache}/corrugation}
    OUT=${OUT:-/tmp/corrugation-e}
    cargo build --release --bin corrugation
    BIN=target/release/corrugation
    mkdir -p "$OUT"
    for r in 3 1 4 2 5; do F=models/reference-described-rpm$r.toml
      "$BIN" passage --model $F --cache "$CACHE" --json --out "$OUT/P-rpm$r" > "$OUT/P-rpm$r.json"
      "$BIN" modes --model $F --cache "$CACHE" --out "$OUT/M-rpm$r" > "$OUT/M-rpm$r.log"
      "$BIN" grow --model $F --cache "$CACHE" --no-coupled --out "$OUT/G-rpm$r" > "$OUT/G-rpm$r.log"
    done
    for r in 3 1 4 2 5; do
      "$BIN" sweep --model models/reference-described-rpm$r.toml --cache "$CACHE" --speeds 54.8:219:1 \
        --out "$OUT/S-rpm$r" > "$OUT/S-rpm$r.log"
    done
    python3 validation/reference_regime_e.py "$OUT" | tee "$OUTDIR/e_summary.txt"
    ;;
  *)
    echo "usage: $0 reflection | a5 [CACHE] | d [CACHE] | e [CACHE]" >&2; exit 2 ;;
esac
