"""Re-run the calling script with Debian's python3 when this interpreter lacks the packages.

The reference scripts need numpy, scipy, mpmath and sympy (Debian: python3-numpy,
python3-scipy, python3-mpmath, python3-sympy). A `python3` found first on PATH (e.g. a
pyenv build) may have none of them; importing this module first then replaces the process
with /usr/bin/python3 running the same script and arguments.
"""
import os
import sys

try:
    import numpy  # noqa: F401
    import scipy  # noqa: F401
    import mpmath  # noqa: F401
    import sympy  # noqa: F401
except ImportError:
    debian = "/usr/bin/python3"
    if os.path.exists(debian) and os.path.realpath(sys.executable) != os.path.realpath(debian):
        os.execv(debian, [debian] + sys.argv)
    raise
