"""freeflex from Python: the compiled module _freeflex and a few conveniences.

    import freeflex
    design = freeflex.load_design("designs/suppress_slew.toml")
    run = freeflex.run(design)            # every study, results only (no files)
    summary = freeflex.summary(design, run)
"""
import json

from ._freeflex import *  # noqa: F401,F403
from ._freeflex import DesignError, IoError, __version__, summary_json  # noqa: F401


def summary(design, result):
    """summary.json of a run, as a dict."""
    return json.loads(summary_json(design, result))
