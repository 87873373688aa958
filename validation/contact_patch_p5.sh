#!/bin/bash
# P5 of validation/contact_patch.md: half-space against fe-patch contact, reduced engine, the
# default model (RPM3) and its RPM1 variant, 140 km/h, smooth rail and the 10 um trial; with
# SET=reference the reference-described RPM3 and RPM1 instead (34 bays, absorbing ends, every
# passage from rest; outputs prefixed ref-; their track modes take 4-8 min and about 11 GB each,
# cold).
# Usage: [SET=reference] bash validation/contact_patch_p5.sh [OUT] (default
# validation/out/contact_patch), then [SET=reference] python3 validation/contact_patch_p5.py OUT.
# Build first: cargo build --release.
# Cost: the first fe-patch run builds the patch of the 32 x 24 grid (about 95 s, 10 GB peak);
# each grow on the fe-patch builds one more for its lengthened grid.
set -u
ROOT=$(cd "$(dirname "$0")/.." && pwd)
B=${CORRUGATION_BIN:-$ROOT/target/release/corrugation}
OUT=${1:-$ROOT/validation/out/contact_patch}
mkdir -p "$OUT" && cd "$OUT"
SET=${SET:-default}
case $SET in default) PRE="";; reference) PRE="ref-";; *) echo "SET: default or reference" >&2; exit 2;; esac
for m in rpm3 rpm1; do
  case $SET-$m in
    default-rpm3) MF="";;
    default-rpm1) MF="--model $ROOT/models/dutch-rpm1.toml";;
    reference-*) MF="--model $ROOT/models/reference-described-$m.toml";;
  esac
  for c in half-space fe-patch; do
    tag=$PRE$m-$c
    if [ ! -f passage-$tag.json ]; then
      /usr/bin/time -v $B passage $MF --no-coupled --no-nodal --set contact.influence=$c --out passage-$tag --json > passage-$tag.json 2> passage-$tag.err
    fi
    /usr/bin/time -v $B grow $MF --no-coupled --amplitudes-um 10 --set contact.influence=$c --out grow-$tag --json > grow-$tag.json 2> grow-$tag.err
    echo "$tag done rc=$?" >> progress.txt
  done
done
