#!/bin/bash
# P5 of validation/contact_patch.md on the explicit engine (the exploration of the lagged split:
# runs on commit ab4a7aa only; the explicit engine refuses the fe-patch since): half-space against fe-patch
# contact, contact grid 32 x 24 (the fe-patch's; the explicit path's selection is not converged
# on it, see the page), fixed wheel, 140 km/h, smooth rail: the default model's RPM3 and RPM1
# (static start), then the reference-described RPM3 and RPM1 (from rest); with TRIAL=1 also the
# default RPM3's 10 um trial (grow --engine explicit). Outputs prefixed as
# validation/contact_patch_p5.sh's, with explicit- and explicit-ref-.
# Usage: bash validation/contact_patch_p5_explicit.sh [OUT] (default
# validation/out/contact_patch), then python3 validation/contact_patch_p5_explicit.py OUT OUT
# (the reduced pair from validation/contact_patch_p5.sh in the same directory).
# Cost (idle, two cores): about 4.5 min per default-model passage, the fe-patches cached by the
# reduced runs (otherwise about 95 s and 10 GB each, built first); about 1.6 GB per passage.
set -u
ROOT=$(cd "$(dirname "$0")/.." && pwd)
B=${CORRUGATION_BIN:-$ROOT/target/release/corrugation}
OUT=${1:-$ROOT/validation/out/contact_patch}
mkdir -p "$OUT" && cd "$OUT"
for m in rpm3 rpm1 ref-rpm3 ref-rpm1; do
  case $m in
    rpm3) MF="";;
    rpm1) MF="--model $ROOT/models/dutch-rpm1.toml";;
    ref-*) MF="--model $ROOT/models/reference-described-${m#ref-}.toml";;
  esac
  for c in half-space fe-patch; do
    tag=explicit-$m-$c
    if [ ! -f $tag.json ] || [ ! -s $tag.json ]; then
      /usr/bin/time -v $B explicit $MF --set contact.influence=$c --out $tag --json > $tag.json 2> $tag.err
      echo "$tag rc=$? $(date -u +%H:%M)" >> progress.txt
    fi
  done
done
if [ -n "${TRIAL:-}" ]; then
  for c in half-space fe-patch; do
    tag=explicit-grow-rpm3-$c
    /usr/bin/time -v $B grow --engine explicit --amplitudes-um 10 --no-rate --set contact.influence=$c --out $tag --json > $tag.json 2> $tag.err
    echo "$tag rc=$? $(date -u +%H:%M)" >> progress.txt
  done
fi
