#!/usr/bin/env bash
# Heavy validation runs, kept out of CI (each is minutes on 2 cores). Run from the repo root:
#   bash validation/run.sh            # everything
#   bash validation/run.sh contact    # one group: contact | modes | moving | bench
# Results are printed; compare them with the expectations in validation/README.md.
set -euo pipefail
cd "$(dirname "$0")/.."
group="${1:-all}"

if [[ "$group" == all || "$group" == contact ]]; then
  echo "== contact: Kalker creep coefficients on a 48x48 grid (within 2 %), Carter on 200 cells"
  cargo test --release --lib contact::tests -- --ignored --nocapture
fi
if [[ "$group" == all || "$group" == modes ]]; then
  echo "== modes: bar-like rail longitudinal modes vs n c/2L; pinned-pinned mode on rigid supports"
  cargo test --release --lib eigen::classify::tests -- --include-ignored --nocapture
  echo "== modes: all track modes below 2 kHz of the default model (Sturm-checked)"
  cargo run --release --example track_modes_bench -- 2000
  echo "== modes: RPM1 for comparison"
  cargo run --release --example track_modes_bench -- 2000 --set fastening.model=RPM1
fi
if [[ "$group" == all || "$group" == moving ]]; then
  echo "== moving: modal synthesis vs direct Newmark on the full K, M, C; static deflection (f_max 0.5-3 kHz)"
  echo "   (model: the 6-bay test track plus MOVING_LOAD_SET=\"k=v,...\" if set)"
  # f_max list: 5 kHz fails on this coarse track (the eigensolver misses modes in 3.4-5 kHz).
  MOVING_LOAD_FMAX="${MOVING_LOAD_FMAX:-500,1000,2000,3000}" \
    cargo test --release --test moving_load -- --ignored --nocapture convergence_table
fi
if [[ "$group" == all || "$group" == bench ]]; then
  echo "== benchmarks"
  cargo run --release --example assembly_bench
  cargo run --release --example contact_bench
  /usr/bin/time -v cargo run --release -- mesh 2>&1 | grep -E "free DOFs|build|Maximum resident|Elapsed"
fi
