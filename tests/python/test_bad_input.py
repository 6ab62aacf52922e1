"""Bad input through Python raises an exception naming what is wrong (the key, the
argument); nothing crashes the interpreter. A fuzz of a few hundred calls with wrong
types, NaN, infinities, empty and misshapen arrays; each must raise TypeError or
ValueError (DesignError is a ValueError) or return a result that says it failed."""
import math
import random

import numpy as np
import pytest

import freeflex as ff

NAN, INF = float("nan"), float("inf")


def body():
    return ff.Body(1.0, 1.0, 1.0, 4, [ff.ForceElement("l", "thruster", 0.0, [0.0, 1.0]),
                                       ff.ForceElement("r", "thruster", 1.0, [0.0, 1.0])])


def test_messages_name_the_key(tmp_path):
    with pytest.raises(ValueError, match="length_m"):
        ff.Body(NAN, 1.0, 1.0)
    with pytest.raises(ValueError, match="ForceElement.type"):
        ff.ForceElement("x", "rocket", 0.0)
    with pytest.raises(ValueError, match="transcription"):
        ff.TrajoptOptions().transcription = "euler"
    with pytest.raises(ValueError, match="TV-LQR method"):
        ff.TvlqrOptions().method = "rk4"
    o = ff.TvlqrOptions()
    o.method = "exponential"
    assert o.method == "exponential"
    bad = tmp_path / "bad.toml"
    bad.write_text('[beam]\nlength_m = -1.0\nmass_kg = 1.0\nbending_stiffness_Nm2 = 1.0\n')
    with pytest.raises(ff.DesignError, match=r"bad\.toml.*line 2.*length_m"):
        ff.load_design(str(bad))
    with pytest.raises(ValueError, match="R must be"):
        m = ff.first_order_model(body(), actuators=[1], until_s=1.0,
                                 loads=ff.Excitation([ff.TimeProfile("steps", [0, 0.5], [0.1]), None]))
        ff.solve_tvlqr(m, 0.0, 1.0, Q=np.eye(2 * body().dofs), R=np.eye(3))


VALUES = [NAN, INF, -INF, -1.0, 0.0, 1e300, "x", None, [], [NAN], np.array([]), np.zeros((0, 0)),
          np.full((3, 3), NAN), [1, 2, 3], {"a": 1}, -7, 2**40]


def calls(rng):
    b = body()
    p = ff.ManeuverProblem()
    pick = lambda: VALUES[rng.randrange(len(VALUES))]  # noqa: E731
    yield lambda: ff.Body(pick(), pick(), pick(), pick())
    yield lambda: ff.Body(1.0, 1.0, 1.0, pick(), [ff.ForceElement("a", "force", pick(), [0.0, 1.0])])
    yield lambda: ff.ForceElement(pick(), pick(), pick(), pick())
    yield lambda: ff.TimeProfile(pick(), pick(), pick())
    yield lambda: ff.TimeProfile("steps", [0.0, pick()], [pick()])
    yield lambda: setattr(p, rng.choice(["u_min", "u_max", "x_final", "duration_s", "actuators", "w_energy"]), pick())
    yield lambda: ff.vibration_weight(b, pick(), pick(), pick())
    yield lambda: ff.vibration_energy(b, pick(), pick())
    yield lambda: ff.tip_deflection(b, pick())
    yield lambda: ff.first_order_model(b, actuators=pick(), until_s=pick())
    yield lambda: ff.simulate_full(b, ff.Excitation([pick(), None]))
    yield lambda: ff.load_design(pick())
    yield lambda: ff.parse_design(pick())
    yield lambda: ff.parse_design("[beam]\nlength_m = " + str(pick()) + "\n")


def test_fuzz_never_crashes():
    rng = random.Random(17)
    kinds = {"raised": 0, "returned": 0}
    for i in range(300):
        fns = list(calls(rng))
        fn = fns[i % len(fns)]
        try:
            r = fn()
        except (TypeError, ValueError, OSError, RuntimeError) as e:
            assert str(e), "an exception without a message"
            kinds["raised"] += 1
            continue
        kinds["returned"] += 1
        if hasattr(r, "ok"):
            assert isinstance(r.ok, bool)
    print(kinds)
    assert kinds["raised"] >= 200  # most random inputs are bad; counted so the fuzz cannot silently test nothing


def test_bad_maneuver_and_law_inputs_raise():
    b = body()
    p = ff.ManeuverProblem()
    p.actuators = [0, 1]
    p.u_min = [-1.0]  # one bound for two actuators
    p.u_max = [1.0, 1.0]
    with pytest.raises(ValueError, match="u_min"):
        ff.solve_maneuver(b, p)
    p.u_min = [-1.0, -1.0]
    p.duration_s = NAN
    with pytest.raises(ValueError, match="duration_s"):
        ff.solve_maneuver(b, p)
    m = ff.first_order_model(b, actuators=[1], until_s=1.0,
                             loads=ff.Excitation([ff.TimeProfile("steps", [0, 0.5], [0.1]), None]))
    n = m.state_size
    with pytest.raises(ValueError):
        ff.solve_tvlqr(m, 0.0, 1.0, Q=np.full((n, n), NAN), R=np.eye(1))
    with pytest.raises(ValueError):
        ff.solve_tvlqr(m, 1.0, 0.0, Q=np.eye(n), R=np.eye(1))
    with pytest.raises(ValueError):
        ff.solve_tvlqr(m, 0.0, 1.0, Q=np.zeros((0, 0)), R=np.eye(1))
    law = ff.solve_tvlqr(m, 0.0, 1.0, Q=np.eye(n), R=np.eye(1))
    assert law.ok, law.message
    with pytest.raises(ValueError):
        ff.simulate_closed_loop_full(m, law, until_s=1.0, limits=[1.0, 2.0])
    with pytest.raises(ValueError):
        ff.simulate_closed_loop_first_order(m, law, until_s=NAN)
    with pytest.raises(ValueError, match="method"):
        ff.simulate_closed_loop_first_order(m, law, until_s=1.0, method="rk4")
    with pytest.raises(ValueError, match="gauss_steps"):
        ff.simulate_closed_loop_first_order(m, law, until_s=1.0, method="gauss", gauss_steps=0)
    with pytest.raises(ValueError, match="CVODES only"):
        ff.simulate_closed_loop_full(m, law, until_s=1.0, method="gauss")
    # the two methods integrate the same loop
    tight = ff.IntegratorOptions()
    tight.method, tight.rtol, tight.atol = "bdf", 1e-12, 1e-14
    cv = ff.simulate_closed_loop_first_order(m, law, until_s=1.0, integrator=tight)
    gauss = ff.simulate_closed_loop_first_order(m, law, until_s=1.0, method="gauss")
    assert cv.ok and gauss.ok
    scale = np.abs(cv.z_dot).max()
    # measured 3.0e-10 of the largest rate (0.32 rad/s): BDF's own error at rtol 1e-12
    # (at the default 1e-8 it is 3.4e-7); the bound is 3x
    assert np.abs(gauss.z_dot - cv.z_dot).max() <= 1e-9 * scale
    with pytest.raises(ValueError):
        law.gain(math.nan)


def test_taylor_first_order_solver_by_name():
    """The perturbation solution by Taylor series, chosen by name as in a design file;
    it agrees with the integrator's and a wrong name is refused naming the key."""
    b = ff.Body(1.0, 1.0, 1.0, 6, [ff.ForceElement("Mz", "torque", 0.5)])
    loads = ff.Excitation([ff.TimeProfile("steps", [0.0, 0.5, 1.0], [1.0, -1.0])])
    o = ff.SimulationOptions()
    o.duration_s = 2.0
    o.integrator.rtol = 1e-10
    o.integrator.atol = 1e-12
    assert o.first_order_solver == "integrator"
    ref = ff.simulate_perturbation(b, loads, o)
    o.first_order_solver = "taylor"
    assert o.first_order_solver == "taylor"
    got = ff.simulate_perturbation(b, loads, o)
    assert got.total.ok and ref.total.ok
    # both are within ~1e-9 of the exact solution at rtol 1e-10 (tests/sim/test_ltv_taylor.cpp)
    assert np.max(np.abs(got.total.z - ref.total.z)) < 1e-8
    with pytest.raises(ValueError, match="first_order_solver"):
        o.first_order_solver = "rk4"


def test_full_model_in_rest_mode_coordinates_by_name():
    """The full model integrated in the coordinates of the modes at rest, chosen by name:
    the same motion as in physical coordinates; the first-order model refuses them."""
    b = ff.Body(1.0, 1.0, 1.0, 10, [ff.ForceElement("Mz", "torque", 0.5)])
    loads = ff.Excitation([ff.TimeProfile("steps", [0.0, 0.5, 1.0], [1.0, -1.0])])
    o = ff.SimulationOptions()
    o.duration_s = 1.0
    o.integrator.method = "dop853"
    o.integrator.rtol = 1e-11
    o.integrator.atol = 1e-13
    assert o.full_variables == "physical" and o.first_order_variables == "modal"
    ref = ff.simulate_full(b, loads, o)
    o.full_variables = "rest_modes"
    got = ff.simulate_full(b, loads, o)
    assert got.ok and ref.ok
    # the two differ by their integration errors, 1e-11 to 1e-10 here (C++ test
    # "rest-mode coordinates: the full model's motion ..."); q itself is 1e-2
    assert np.max(np.abs(got.z - ref.z)) < 2e-9
    with pytest.raises(ValueError, match="full_variables"):
        o.full_variables = "eigen"
    o.first_order_variables = "rest_modes"
    with pytest.raises(ValueError, match="first_order_variables"):
        ff.simulate_perturbation(b, loads, o)
