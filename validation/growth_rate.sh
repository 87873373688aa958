#!/usr/bin/env bash
# The growth-rate spectrum against passages over 1 µm sinusoidal corrugations on the default
# model at 140 km/h (case D of validation/growth_rate.md). Writes validation/out/growth_rate/.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --profile test-opt
out=validation/out/growth_rate
mkdir -p "$out"
target/test-opt/corrugation grow --rate-check 20,35,50,65,80 --out "$out/default_140" \
  2>&1 | grep -v running | tee "$out/default_140.log"
