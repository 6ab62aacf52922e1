#!/usr/bin/env bash
# The sweep's result bytes do not depend on how it ran (run by CTest):
#   test_sweep.sh threads FREEFLEX DESIGN WORK          1 thread against 2 threads
#   test_sweep.sh resume  FREEFLEX DESIGN WORK          killed (SIGKILL) half way, rerun, against one run
#   test_sweep.sh mpi     FREEFLEX DESIGN WORK FREEFLEX_MPI MPIEXEC   mpirun -np 2 against one process
# Compared: every CSV file (summary.json holds wall times; figures are off in the design).
set -euo pipefail
mode=$1 exe=$2 design=$3 work=$4
rm -rf "$work"
mkdir -p "$work"
same() {  # same CSV bytes in two output directories
  local a=$1 b=$2 n=0
  for f in "$a"/*.csv; do
    cmp "$f" "$b/$(basename "$f")" || { echo "differs: $(basename "$f")"; return 1; }
    n=$((n + 1))
  done
  ((n > 0)) || { echo "no CSV files in $a"; return 1; }
  echo "$n CSV files identical"
}
"$exe" run "$design" --out "$work/one" --threads 1 --quiet
case $mode in
  threads)
    "$exe" run "$design" --out "$work/two" --threads 2 --quiet
    same "$work/one" "$work/two"
    ;;
  resume)
    total=$(grep -c . "$work/one/sweep.csv")  # header + samples
    half=$(((total - 1) / 2))
    "$exe" run "$design" --out "$work/killed" --threads 1 --quiet &
    pid=$!
    journal="$work/killed/.freeflex-sweep-journal"
    for _ in $(seq 1 600); do  # up to 60 s
      if [[ -f $journal ]] && (($(wc -l < "$journal") > half)); then break; fi
      sleep 0.1
    done
    kill -9 "$pid" 2> /dev/null || { echo "the run ended before it could be killed"; exit 1; }
    wait "$pid" 2> /dev/null || true
    done_before=$(grep -c " end$" "$journal" || true)  # a last line cut before its newline still counts
    [[ ! -f $work/killed/sweep.csv ]] || { echo "a killed run left sweep.csv"; exit 1; }
    out=$("$exe" run "$design" --out "$work/killed" --threads 1)
    echo "$out" | grep "from the journal"
    echo "$out" | grep -q ", $done_before from the journal)" || { echo "expected $done_before samples from the journal"; exit 1; }
    [[ ! -f $journal ]] || { echo "the journal outlived the finished run"; exit 1; }
    same "$work/one" "$work/killed"
    ;;
  mpi)
    mpi_exe=$5 mpiexec=${6:-mpirun}
    "$mpiexec" --allow-run-as-root --oversubscribe -np 2 "$mpi_exe" "$design" --out "$work/mpi" --threads 1 --quiet
    same "$work/one" "$work/mpi"
    grep -q '"ranks": 2' "$work/mpi/summary.json" || { echo "summary.json does not say 2 ranks"; exit 1; }
    ;;
  *) echo "unknown mode $mode"; exit 2 ;;
esac
