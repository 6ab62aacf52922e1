#!/usr/bin/env bash
# Runs every shipped design with a freeflex binary and compares the files it writes with
# those of a reference run, byte for byte: the check that a refactor or an added option
# leaves every result as it was.
#
#   scripts/compare_outputs.sh make FREEFLEX REF_DIR       # reference run into REF_DIR
#   scripts/compare_outputs.sh check FREEFLEX REF_DIR      # run again, compare with REF_DIR
#
# Compared: every file a run writes (CSV tables, gnuplot scripts, Ipopt logs) except the
# PNG figures (their bytes carry cairo's timestamps) and summary.json (it holds wall
# times). Designs named in FREEFLEX_DESIGNS (space-separated stems) replace the default
# list, every designs/*.toml. Exit 0 when everything matches, 1 otherwise.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
if (($# != 3)) || [[ $1 != make && $1 != check ]]; then
  echo "usage: $0 make|check FREEFLEX REF_DIR" >&2
  exit 2
fi
mode=$1 exe=$2 ref=$3
if [[ -n ${FREEFLEX_DESIGNS:-} ]]; then
  read -r -a designs <<< "$FREEFLEX_DESIGNS"
else
  designs=()
  for f in "$root"/designs/*.toml; do designs+=("$(basename "$f" .toml)"); done
fi
out=$ref
if [[ $mode == check ]]; then
  out=$(mktemp -d)
  trap 'rm -rf "$out"' EXIT
fi
status=0
for d in "${designs[@]}"; do
  set +e
  "$exe" run "$root/designs/$d.toml" --out "$out/$d" --quiet > /dev/null 2>&1
  rc=$?
  set -e
  echo "$rc" > "$out/$d/.exit-code" 2> /dev/null || { echo "$d: no output directory (exit $rc)"; status=1; continue; }
  [[ $mode == make ]] && { echo "$d: exit $rc"; continue; }
  if [[ ! -d $ref/$d ]]; then echo "$d: not in the reference $ref"; status=1; continue; fi
  mismatch=0
  while IFS= read -r f; do
    name=${f#"$ref/$d/"}
    if [[ ! -f $out/$d/$name ]]; then echo "$d: $name missing"; mismatch=1
    elif ! cmp -s "$f" "$out/$d/$name"; then echo "$d: $name differs"; mismatch=1; fi
  done < <(find "$ref/$d" -type f ! -name '*.png' ! -name summary.json ! -name '.freeflex-*' | sort)
  while IFS= read -r f; do
    name=${f#"$out/$d/"}
    [[ -f $ref/$d/$name ]] || { echo "$d: $name is new"; mismatch=1; }
  done < <(find "$out/$d" -type f ! -name '*.png' ! -name summary.json ! -name '.freeflex-*' | sort)
  if ((mismatch)); then status=1; else echo "$d: identical"; fi
done
exit $status
