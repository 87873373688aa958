#!/bin/bash
# P5 of validation/contact_patch.md: half-space against fe-patch contact, reduced engine, the
# default model (RPM3) and its RPM1 variant, 140 km/h, smooth rail and the 10 um trial.
# Usage: bash validation/contact_patch_p5.sh [OUT] (default validation/out/contact_patch), then
# python3 validation/contact_patch_p5.py OUT. Build first: cargo build --release.
# Cost: the first fe-patch run builds the patch of the 32 x 24 grid (about 95 s, 10 GB peak);
# each grow on the fe-patch builds one more for its lengthened grid.
set -u
ROOT=$(cd "$(dirname "$0")/.." && pwd)
B=${CORRUGATION_BIN:-$ROOT/target/release/corrugation}
OUT=${1:-$ROOT/validation/out/contact_patch}
mkdir -p "$OUT" && cd "$OUT"
for m in rpm3 rpm1; do
  case $m in rpm3) MF="";; rpm1) MF="--model $ROOT/models/dutch-rpm1.toml";; esac
  for c in half-space fe-patch; do
    tag=$m-$c
    if [ ! -f passage-$tag.json ]; then
      /usr/bin/time -v $B passage $MF --no-coupled --no-nodal --set contact.influence=$c --out passage-$tag --json > passage-$tag.json 2> passage-$tag.err
    fi
    /usr/bin/time -v $B grow $MF --no-coupled --amplitudes-um 10 --set contact.influence=$c --out grow-$tag --json > grow-$tag.json 2> grow-$tag.err
    echo "$tag done rc=$?" >> progress.txt
  done
done
