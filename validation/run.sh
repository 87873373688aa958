#!/usr/bin/env bash
# Heavy validation runs, kept out of CI (each is minutes on 2 cores). Run from the repo root:
#   bash validation/run.sh            # everything
#   bash validation/run.sh contact    # one group: contact | patch | modes | moving | explicit | selection | bench
# Results are printed; compare them with the expectations in validation/README.md.
set -euo pipefail
cd "$(dirname "$0")/.."
group="${1:-all}"

if [[ "$group" == all || "$group" == contact ]]; then
  echo "== contact: Kalker creep coefficients on a 48x48 grid (within 2 %), Carter on 200 cells"
  cargo test --release --lib contact::tests -- --ignored --nocapture
fi
if [[ "$group" == all || "$group" == patch ]]; then
  echo "== patch: the local FE contact patch (validation/contact_patch.md): the flat block against"
  echo "   Boussinesq-Cerruti (P1, ~25 min, up to ~6 GB), the rail head's kernel against the half-space (P2b, ~7 min),"
  echo "   Hertz on the FE kernels (P2, ~8 min, 9 GB), the split (P3: ~20 min and 15 GB at 15 kN, ~32 min and 18 GB at 100 kN; the tread ~1 min),"
  echo "   the local compliance against the half-space's (P6, ~3 and ~8 min), the penalty contact's static Hertz problem"
  echo "   on the refined bodies (P4a, ~2 min, 7 GB) and on the central-difference step (P4b, seconds)"
  cargo test --profile test-opt --lib flat_block_convergence_table -- --ignored --nocapture
  CASE="0.8 3 4 4" cargo test --profile test-opt --lib rail_head_kernel_against_the_half_space -- --ignored --nocapture
  CASE="0.8 3 15" cargo test --profile test-opt --lib hertz_on_the_rail_head_patch -- --ignored --nocapture
  CASE="0.8 2 100" cargo test --profile test-opt --lib hertz_on_the_rail_head_patch -- --ignored --nocapture
  CASE="0.8 3 15 0.3 0.1 0.05" cargo test --profile test-opt --lib split_case -- --ignored --nocapture
  CASE="0.8 3 100 0.2 0.1" cargo test --profile test-opt --lib split_case -- --ignored --nocapture
  cargo test --profile test-opt --lib tread_split_against_the_global_mesh -- --ignored --nocapture
  CASE="0.8 3 15" cargo test --profile test-opt --lib local_compliance_against_the_half_space -- --ignored --nocapture
  CASE="0.8 3 100" cargo test --profile test-opt --lib local_compliance_against_the_half_space -- --ignored --nocapture
  CASE="0.8 0.533 0.4 15" cargo test --profile test-opt --lib penalty_static_case -- --ignored --nocapture
  cargo test --profile test-opt --lib explicit::penalty_tests -- --nocapture
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
if [[ "$group" == all || "$group" == explicit ]]; then
  echo "== explicit: the energy ledger against the replayed nodal work (fine mesh), the coupled passage over 0.6 m, the rotating"
  echo "   wheel without spin against the fixed wheel (the heavy tests kept out of CI)"
  cargo test --profile test-opt --test explicit --test explicit_rotating -- --ignored --nocapture
fi
if [[ "$group" == all || "$group" == selection ]]; then
  echo "== selection: which modes set the frequency selection? (validation/frequency_selection.md)"
  echo "   default track, f_max 2 kHz: wheel steel density 7800 vs 9000 kg/m^3; a wheel mode moves"
  echo "   by sqrt(7800/9000) = 0.931, a track mode not at all"
  bin=target/release/corrugation
  cargo build --release
  out="${SELECTION_OUT:-validation/out/selection}"
  for rho in 7800 9000; do
    $bin sweep --set run.fmax=2000 --set wheel.density=$rho --speeds 110:219:12 \
      --out "$out/rho$rho" --json > "$out-rho$rho.json"
    python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(sys.argv[2], [round(f) for f in d['dominant_frequency_hz']])" \
      "$out-rho$rho.json" "rho $rho: dominant Hz"
  done
  $bin receptance --set run.fmax=2000 --to-hz 2000 --out "$out/receptance"
fi
if [[ "$group" == all || "$group" == bench ]]; then
  echo "== benchmarks"
  cargo run --release --example assembly_bench
  cargo run --release --example contact_bench
  /usr/bin/time -v cargo run --release -- mesh 2>&1 | grep -E "free DOFs|build|Maximum resident|Elapsed"
  echo "== eigen: all track modes of the default model below 5 kHz, cold (docs/performance.md)"
  cargo build --release --example track_modes_bench
  /usr/bin/time -v target/release/examples/track_modes_bench 5000 2>&1 \
    | grep -E "modes|eigen total|orthogonalisation|slice|peak|Maximum resident|Elapsed"
  echo "== eigen: orderings (fill, factorisation) and block-solve cost per vector"
  target/release/examples/track_modes_bench 5000 --probe
fi
