#!/usr/bin/env bash
# Convergence of the key track frequencies of RPM3 (docs/theory.md §3.3):
#   * the pinned-pinned frequency (vertical bending, nodes at the sleepers);
#   * the lowest longitudinal-compression (LC) frequencies;
# versus the mesh refinement (3 levels) and versus the width of the rigidly held strip
# (`fastening.strip_width`, 5-40 mm).
#
# Each case extracts all modes in [F_MIN, F_MAX] Hz with the Sturm-checked solver and
# classifies them (examples/track_modes_bench.rs --classify); the `KEY` lines name the
# pinned-pinned, LC and LS modes and the sleeper modes whose rail motion is LC.
# The study uses a 4-bay track (2.4 m) so that every case is minutes, not tens of minutes, on
# 2 cores; the default 16-bay track at the default mesh is run once for comparison.
#
# Run from the repo root:  bash validation/modes_convergence.sh [mesh|strip|pp|pp16|lcband|full]
# Output: validation/out/modes_*.txt (raw) and a table on stdout.
set -euo pipefail
cd "$(dirname "$0")/.."
what="${1:-all}"
F_MIN="${F_MIN:-900}"
F_MAX="${F_MAX:-5000}"
mkdir -p validation/out
cargo build --release --example track_modes_bench
bin=target/release/examples/track_modes_bench

run() { # name, then --set arguments
  local name=$1; shift
  local out=validation/out/modes_$name.txt
  if [[ ! -s $out ]]; then
    EIGEN_FMIN=$F_MIN /usr/bin/time -f "wall %e s, peak %M KB" "$bin" "$F_MAX" --classify "$@" >"$out" 2>&1
  fi
  local pp lc
  pp=$(grep '^KEY pinned_pinned' "$out" | awk '{print $4}' | head -3 | paste -sd' ' || true)
  lc=$(grep '^KEY LC ' "$out" | awk '{print $4}' | head -5 | paste -sd' ' || true)
  local dofs
  dofs=$(grep -o 'free DOFs [0-9]*' "$out" | awk '{print $3}' || true)
  printf '%-28s %8s  pinned-pinned: %-22s LC: %s\n' "$name" "$dofs" "${pp:--}" "${lc:--}"
}

B="--set track.bays=4"
if [[ $what == all || $what == mesh ]]; then
  echo "== mesh refinement (4 bays, strip 20 mm): coarse / default / fine"
  run mesh_coarse $B --set mesh.element_length=0.06 --set mesh.fine_element_length=0.04 --set mesh.section_size=0.03 --set mesh.head_size=0.015
  run mesh_default $B
  run mesh_fine $B --set mesh.element_length=0.027 --set mesh.fine_element_length=0.013 --set mesh.section_size=0.014 --set mesh.head_size=0.007
fi
if [[ $what == all || $what == strip ]]; then
  echo "== strip width (4 bays, default mesh)"
  for w in 0.005 0.01 0.02 0.035; do  # 0.035 m = the largest allowed (one grid cell)
    run strip_$w $B --set fastening.strip_width=$w
  done
  echo "== strip width 5 mm, fine mesh (does a narrow strip converge?)"
  run strip_0.005_fine $B --set fastening.strip_width=0.005 --set mesh.element_length=0.027 --set mesh.fine_element_length=0.013 --set mesh.section_size=0.014 --set mesh.head_size=0.007
fi
if [[ $what == all || $what == pp ]]; then
  # The pinned-pinned band only (cheap): 700-1700 Hz, the VB lines give wavelength and the
  # ratio of the deflection at the sleepers to its RMS (node_ratio; 0 = nodes at sleepers).
  echo "== pinned-pinned band 700-1700 Hz vs mesh (4 bays, strip 20 mm)"
  export F_MIN=700 F_MAX=1700
  run pp_mesh_coarse $B --set mesh.element_length=0.06 --set mesh.fine_element_length=0.04 --set mesh.section_size=0.03 --set mesh.head_size=0.015
  run pp_mesh_default $B
  run pp_mesh_fine $B --set mesh.element_length=0.027 --set mesh.fine_element_length=0.013 --set mesh.section_size=0.014 --set mesh.head_size=0.007
  for f in validation/out/modes_pp_*.txt; do
    echo "-- $f"; grep '^KEY VB' "$f" || true
  done
fi
if [[ $what == all || $what == pp16 ]]; then
  # The 4-bay rail is too short for a clean pinned-pinned standing wave (no VB mode there has
  # its nodes at the sleepers): the pinned-pinned convergence uses the 16-bay track in a
  # narrow band around it.
  echo "== pinned-pinned band 1150-1350 Hz vs mesh (16 bays, strip 20 mm)"
  export F_MIN=1150 F_MAX=1350
  run pp16_mesh_coarse --set mesh.element_length=0.06 --set mesh.fine_element_length=0.04 --set mesh.section_size=0.03 --set mesh.head_size=0.015
  run pp16_mesh_default
  run pp16_mesh_fine --set mesh.element_length=0.027 --set mesh.fine_element_length=0.013 --set mesh.section_size=0.014 --set mesh.head_size=0.007
  for f in validation/out/modes_pp16_*.txt; do
    echo "-- $f"; grep '^KEY VB' "$f" || true
  done
fi
if [[ $what == all || $what == lcband ]]; then
  # The lowest LC modes are coupled with vertical bending (amplitudes LC ≈ 0.7, V ≈ 0.65 at
  # 20 mm): with a wider strip some of them tip over to `vertical_bending`. The VB_with_LC
  # lines list those (VB family, section-mean u_x amplitude ≥ 0.5).
  echo "== 1900-3000 Hz, coupled LC/VB modes vs strip width (4 bays, default mesh)"
  export F_MIN=1900 F_MAX=3000
  for w in 0.005 0.02 0.035; do
    run lcband_$w $B --set fastening.strip_width=$w
  done
  for f in validation/out/modes_lcband_*.txt; do
    echo "-- $f"; grep -E '^KEY (LC|VB_with_LC) ' "$f" | awk '{print $2, $4, $12}' || true
  done
fi
if [[ $what == all || $what == full ]]; then
  echo "== default model (16 bays), all modes to F_MAX"
  F_MIN=0 run full16 
fi
