"""Shared fixtures of the Python tests: the program, the source tree, a design runner."""
import os
import pathlib
import subprocess

import pytest

SOURCE = pathlib.Path(os.environ.get("FREEFLEX_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
CLI = os.environ.get("FREEFLEX_CLI", str(SOURCE / "build" / "freeflex"))


@pytest.fixture(scope="session")
def source_dir():
    return SOURCE


def run_cli(design_path, out_dir):
    """`freeflex run DESIGN --out OUT`; returns the completed process (checked)."""
    p = subprocess.run([CLI, "run", str(design_path), "--out", str(out_dir), "--quiet"], capture_output=True,
                       text=True)
    assert p.returncode == 0, p.stderr
    return p


def slew_design(tmp_path, extra_controller="", export=None):
    """designs/suppress_slew.toml with extra [controller] keys and an [export] section."""
    text = (SOURCE / "designs" / "suppress_slew.toml").read_text()
    text = text.split("\n[export]")[0]
    if extra_controller:
        text = text.replace("[controller]\n", "[controller]\n" + extra_controller + "\n")
    if export is not None:
        text += "\n[export]\n" + export + "\n"
    path = tmp_path / "slew.toml"
    path.write_text(text)
    return path
