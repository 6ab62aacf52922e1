#!/usr/bin/env bash
# Main job: install what is missing, build freeflex in Release, reproduce the paper, then
# run the workbench's chain on a shipped example (designs/suppress_slew.toml: minimum-energy
# slew -> the vibration it leaves -> TV-LQR against open loop on the full model) and end
# with a table of the key figures and where the files are.
# Results go to results/<design name>/ under the repository (override with FREEFLEX_RESULTS).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$root/scripts/install_deps.sh"
cmake -S "$root" -B "$root/build" -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=OFF > /dev/null
cmake --build "$root/build" -j "$(nproc)" --target freeflex_cli
results=${FREEFLEX_RESULTS:-$root/results}
for design in paper_table1 paper_force_pulse paper_moment_pulse suppress_slew; do
  echo "== freeflex run designs/$design.toml"
  "$root/build/freeflex" run "$root/designs/$design.toml" --out "$results/$design"
done
echo
echo "freeflex: results in $results/ (one folder per design; summary.json in each)"
echo
python3 "$root/scripts/workbench_table.py" "$results"
