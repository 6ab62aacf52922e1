#!/usr/bin/python3
"""Reference for the sweep's confidence intervals (tests/app/test_sweep_statistics.cpp).

Wilson score intervals (95%) of binomial proportions k of n, computed by SciPy's
binomtest(k, n).proportion_ci(0.95, "wilson"), an implementation that shares nothing with
freeflex's wilson_interval. Writes tests/reference/sweep_intervals.csv (k, n, low, high).
Run from the repository root: python3 scripts/reference/sweep_intervals.py"""
import os
import sys

try:
    from scipy.stats import binomtest
except ImportError:  # a python3 without SciPy: Debian's has it
    if sys.executable != "/usr/bin/python3":
        os.execv("/usr/bin/python3", ["/usr/bin/python3"] + sys.argv)
    raise

CASES = [(86, 1000), (0, 40), (40, 40), (1282, 15000), (1, 3), (500, 1000)]

with open(os.path.join("tests", "reference", "sweep_intervals.csv"), "w") as f:
    f.write("k,n,low,high\n")
    for k, n in CASES:
        ci = binomtest(k, n).proportion_ci(0.95, "wilson")
        f.write(f"{k},{n},{ci.low!r},{ci.high!r}\n")
