#!/usr/bin/env bash
# Main job: install what is missing, build freeflex in Release, reproduce the paper.
# Results go to results/<design name>/ under the repository (override with FREEFLEX_RESULTS).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$root/scripts/install_deps.sh"
cmake -S "$root" -B "$root/build" -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=OFF > /dev/null
cmake --build "$root/build" -j "$(nproc)" --target freeflex_cli
results=${FREEFLEX_RESULTS:-$root/results}
for design in paper_table1 paper_force_pulse paper_moment_pulse; do
  echo "== freeflex run designs/$design.toml"
  "$root/build/freeflex" run "$root/designs/$design.toml" --out "$results/$design"
done
echo
echo "freeflex: the paper's reproduction is in $results/ (one folder per design; summary.json in each)"
