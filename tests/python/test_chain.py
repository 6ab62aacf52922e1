"""From Python only: the minimum-energy slew of designs/suppress_slew.toml, the TV-LQR
about it and the closed loop on the full nonlinear model, built step by step from the
module's calls, give the numbers `freeflex run` gives for the design (its .mat export)."""
import importlib.util
import os
import subprocess
import sys

import numpy as np
import scipy.io

import freeflex as ff
from conftest import SOURCE, run_cli, slew_design


def python_chain():
    """examples/python/slew_tvlqr.py's chain."""
    spec = importlib.util.spec_from_file_location("slew_tvlqr", SOURCE / "examples" / "python" / "slew_tvlqr.py")
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    _, _, opt, law, closed, first = example.slew_chain()
    assert opt.ok, opt.message
    assert law.ok, law.message
    return opt, law, closed, first


def test_python_chain_equals_freeflex_run(tmp_path):
    design = slew_design(tmp_path, export='formats = ["mat"]\ncontents = ["gains", "histories"]')
    run_cli(design, tmp_path / "out")
    d = scipy.io.loadmat(tmp_path / "out" / "controller.mat")
    opt, law, closed, first = python_chain()
    assert abs(opt.objective - 0.9233) < 1e-3  # the energy optimum of examples/optimal_slew.cpp
    worst = {
        "K": np.abs(law.K - np.moveaxis(d["K"], 2, 0)).max(),
        "u_ff": np.abs(law.feedforward - d["u_ff"]).max(),
        "full z": np.abs(closed.z - d["tvlqr_nonlinear_z"]).max(),
        "full z_dot": np.abs(closed.z_dot - d["tvlqr_nonlinear_z_dot"]).max(),
        "full commands": np.abs(closed.commands - d["tvlqr_nonlinear_u"]).max(),
        "first-order z": np.abs(first.z - d["tvlqr_first_order_z"]).max(),
    }
    print("Python chain vs freeflex run, max |difference|:", worst)
    assert np.array_equal(closed.t, d["tvlqr_nonlinear_t"].ravel())
    # the same library calls with the same inputs: measured 0 (bit for bit); 1e-12 is the
    # acceptance bound
    for what, diff in worst.items():
        assert diff <= 1e-12, what


def test_one_call_chain_and_design_run_agree(tmp_path):
    design = ff.load_design(str(slew_design(tmp_path)))
    run = ff.run(design)
    assert run.ok, run.message
    cases = {(c.name, c.model): c for c in run.suppression.cases}
    full = cases[("tvlqr", "nonlinear")]
    _, _, closed, _ = python_chain()
    assert np.array_equal(full.z, closed.z)  # same calls, same numbers: measured bit for bit
    s = ff.summary(design, run)
    assert s["studies"]["suppression"]["cases"][3]["case"] == "tvlqr"
    # every flight estimates its error (the chain again at 10x tighter tolerances)
    for c in run.suppression.cases:
        assert np.isfinite(c.energy_error_estimate_J) and c.energy_error_estimate_J >= 0.0, (c.name, c.model)
    assert full.energy_error_estimate_J < 1e-2 * full.residual_vibration_energy_J  # converged: measured 5e-4
    assert s["studies"]["suppression"]["cases"][3]["residual_vibration_energy_error_estimate_J"] == \
        full.energy_error_estimate_J


def test_example_script_makes_its_figure(tmp_path):
    png = tmp_path / "slew.png"
    p = subprocess.run([sys.executable, str(SOURCE / "examples" / "python" / "slew_tvlqr.py"), str(png)],
                       capture_output=True, text=True, env=dict(os.environ, MPLBACKEND="Agg"))
    assert p.returncode == 0, p.stderr
    assert png.stat().st_size > 10000
    assert "TV-LQR" in p.stdout


def test_elastic_maneuver_names_the_modes_its_mesh_cannot_resolve(tmp_path):
    """designs/slew_energy_at_rest.toml holds 2 modes on 200 intervals over 3 s (h = 15 ms,
    omega_2 h = 0.93): resolved. Holding every coordinate of its NOA 6 model instead,
    modes 4..6 (omega h = 3.0 .. 9.8) are not, and the run says so."""
    text = (SOURCE / "designs" / "slew_energy_at_rest.toml").read_text()
    text = text[: text.index("[simulation]")]  # the maneuver only
    shipped = tmp_path / "shipped.toml"
    shipped.write_text(text)
    run = ff.run(ff.load_design(str(shipped)))
    assert run.ok, run.message
    r = run.maneuver.trajopt
    assert run.maneuver.replay.ok and not run.maneuver.replay.flagged
    assert run.maneuver.replay.position_miss_m < 1e-6  # 200 Hermite-Simpson intervals: 4e-9 m measured
    assert len(r.mode_frequencies) == 2 and r.unresolved_modes == []
    assert r.unresolved_modes_message == ""
    assert r.x_elastic.shape[0] == len(r.t)
    # the optimizer's own model at rest: its rest constraints hold to Ipopt's constraint
    # tolerance (1e-8), so at most about 1e-16 J (measured: 0 to 1e-55)
    assert r.terminal_vibration_energy_J < 1e-14

    held = tmp_path / "all.toml"
    # (500 Ipopt iterations at most keep the larger problem within the work bound)
    held.write_text(text.replace("elastic_modes = 2 ", 'max_iterations = 500\nelastic_modes = "all" '))
    run = ff.run(ff.load_design(str(held)))
    assert run.ok, run.message
    r = run.maneuver.trajopt
    assert len(r.mode_frequencies) == 6
    assert r.unresolved_modes == [3, 4, 5]
    assert "elastic_modes = 3" in r.unresolved_modes_message
    assert any("does not resolve elastic modes 4..6" in w for w in run.warnings)


def test_vibration_aware_slew_in_one_call_starts_from_the_rigid_optimum():
    """The two-thruster slew with every elastic coordinate of a NOA 4 beam at rest at T,
    set up and solved from Python: by default it starts from its rigid counterpart's
    optimum (fewer Ipopt iterations, the same optimum)."""
    b = ff.Body(1.0, 1.0, 1.0, 4, [ff.ForceElement("left", "thruster", 0.0, [0.0, 1.0]),
                                   ff.ForceElement("right", "thruster", 1.0, [0.0, 1.0])])
    p = ff.ManeuverProblem()
    p.actuators = [0, 1]
    p.u_min = [-1.0, -1.0]
    p.u_max = [1.0, 1.0]
    p.x_final = [1.0, 0.5, 0.5 * np.pi, 0.0, 0.0, 0.0]
    p.duration_s = 3.0
    p.elastic = True
    p.modes_at_rest = -1
    o = ff.TrajoptOptions()
    o.transcription = "hermite_simpson_compressed"
    o.intervals = 60
    warm = ff.solve_maneuver(b, p, o)
    o.coarse_start = False
    cold = ff.solve_maneuver(b, p, o)
    assert warm.ok and cold.ok, (warm.message, cold.message)
    assert warm.warm_started and warm.warm_start_iterations > 0
    assert not cold.warm_started and cold.warm_start_iterations == 0
    assert warm.iterations < cold.iterations  # measured 9 against 17
    # one optimum: Ipopt's tol 1e-8 leaves about 1e-9 in J
    assert abs(warm.objective - cold.objective) < 1e-7 * abs(cold.objective)
    assert warm.terminal_vibration_energy_J < 1e-14  # at rest to Ipopt's constraint tolerance


def test_lqg_and_sweep_results_with_their_error_estimates():
    """tests/data/sweep_small.toml run from Python: the sweep's samples and statistics and
    its integration checks; with a gyro and an [lqg], the LQG flights and their estimates,
    the same numbers summary.json gives."""
    text = (SOURCE / "tests" / "data" / "sweep_small.toml").read_text()
    design = ff.parse_design(text, "sweep_small.toml")
    run = ff.run(design)
    assert run.ok, run.message
    sw = run.sweep
    s = ff.summary(design, run)["studies"]["sweep"]
    assert sw.values.shape == (s["samples"], len(sw.parameter_names))
    assert np.isfinite(sw.residual_vibration_energy_J).all()
    assert sw.fraction_meeting == s["fraction_meeting_requirement"]
    assert 1 <= len(sw.error_checks) <= 4 and sw.error_checks[0].role == "median"
    for c in sw.error_checks:  # each check's energy is its sample's own
        assert c.energy_J == sw.residual_vibration_energy_J[c.index]
    assert sw.max_relative_error_estimate == s["integration_error_estimate"]["max_relative_change"]

    text = text[: text.index("[sweep]")] + \
        '[[sensor]]\nname = "gyro"\ntype = "gyro_attitude"\nnoise_density = 1e-5\n[lqg]\nsample_rate_hz = 2000\n'
    design = ff.parse_design(text, "lqg_small.toml")
    run = ff.run(design)
    assert run.ok, run.message
    assert [c.name for c in run.lqg.cases] == ["tvlqr_sampled", "digital_tvlqr", "lqg"]
    cases = ff.summary(design, run)["studies"]["lqg"]["cases"]
    for c in run.lqg.cases:
        assert np.isfinite(c.energy_error_estimate_J)
        assert c.energy_error_estimate_J == cases[c.name]["residual_vibration_energy_error_estimate_J"]
    assert run.lqg.open_loop_energy_J > 0.0
