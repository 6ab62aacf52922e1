"""Example: the workbench's chain from Python, on the beam of designs/suppress_slew.toml.

A 1 m, 1 kg, EI = 1 N m^2 free-free beam with body-fixed thrusters at both tips
(|u| <= 1 N) slews from rest at the origin to rest at (1 m, 0.5 m, 90 deg) in 3 s at
least energy (Hermite-Simpson, 100 intervals, Ipopt). The slew leaves the beam
vibrating; a TV-LQR on the same thrusters, designed on the first-order model about the
slew over 5 s, adds feedback. Both are flown on the full nonlinear model.
Writes slew_tvlqr.png (tip deflection, vibration energy, commands against their limits).
Expected: the energy optimum J = 0.9233 N^2 s; the vibration energy left at 5 s falls
from ~1.4e-2 J open loop to ~1e-8 J under the TV-LQR.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/slew_tvlqr.py [out.png]
"""
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import freeflex as ff  # noqa: E402


def slew_chain():
    """The slew, the TV-LQR and the closed loops, step by step (first-order model,
    solve_tvlqr, simulate_closed_loop_*), as `freeflex run designs/suppress_slew.toml`
    does them."""
    body = ff.Body(length_m=1.0, mass_kg=1.0, bending_stiffness_Nm2=1.0, noa=6,
                   elements=[ff.ForceElement("thruster_left", "thruster", 0.0, [0.0, 1.0]),
                             ff.ForceElement("thruster_right", "thruster", 1.0, [0.0, 1.0])])
    slew = ff.ManeuverProblem()
    slew.actuators = [0, 1]
    slew.u_min, slew.u_max = [-1.0, -1.0], [1.0, 1.0]
    slew.x_final = [1.0, 0.5, 90.0 * np.pi / 180.0, 0.0, 0.0, 0.0]  # degrees converted as the design reader does
    slew.duration_s = 3.0
    opt = ff.solve_maneuver(body, slew)  # defaults: hermite_simpson, 100 intervals
    model = ff.first_order_model(body, maneuver=ff.flown_maneuver(opt, slew), actuators=[0, 1])
    law = ff.solve_tvlqr(model, 0.0, 5.0, Q=ff.vibration_weight(body, 10.0, 10.0, 1.0), R=np.eye(2))
    closed = ff.simulate_closed_loop_full(model, law, until_s=5.0, limits=[1.0, 1.0])
    first = ff.simulate_closed_loop_first_order(model, law, until_s=5.0, limits=[1.0, 1.0])
    return body, slew, opt, law, closed, first


def main(out):
    body, slew, opt, law, closed, _ = slew_chain()
    print(f"slew: {opt.status}, J = {opt.objective:.4f} N^2 s; TV-LQR {law.message}; closed loop "
          f"{'completed' if closed.ok else closed.message}")
    # open loop on the full model: the slew's commands alone (suppress_vibration's open loop)
    p = ff.SuppressionProblem()
    p.maneuver, p.actuators, p.limits = ff.flown_maneuver(opt, slew), [0, 1], [1.0, 1.0]
    p.Q, p.R, p.horizon_s, p.until_s = ff.vibration_weight(body, 10.0, 10.0, 1.0), np.eye(2), 5.0, 5.0
    chain = ff.suppress_vibration(body, p)
    runs = {"open loop": (chain.open_loop_full.t, chain.open_loop_full.z, chain.open_loop_full.z_dot),
            "TV-LQR": (closed.t, closed.z, closed.z_dot)}

    fig, ax = plt.subplots(3, 1, figsize=(8, 9), sharex=True)
    for name, (t, z, zd) in runs.items():
        e = ff.vibration_energy(body, z, zd)
        tip = ff.tip_deflection(body, z)[:, 1]
        ax[0].plot(t, tip, label=name)
        ax[1].semilogy(t, np.where(e > 0, e, np.nan), label=name)  # at rest at t = 0: no energy to draw
        print(f"{name:10s} E_vib(5 s) = {e[-1]:.3e} J")
    for k, lbl in enumerate(["left", "right"]):
        ax[2].plot(closed.t, closed.commands[:, k], label=f"TV-LQR, thruster {lbl}")
    for lim in (-1.0, 1.0):
        ax[2].axhline(lim, color="k", ls="--", lw=0.8)
    ax[2].set_ylim(-1.2, 1.2)
    ax[0].set_ylabel("tip deflection, right end [m]")
    ax[1].set_ylabel("vibration energy [J]")
    ax[2].set_ylabel("command [N] (limits dashed)")
    ax[2].set_xlabel("t [s]")
    for a in ax:
        a.legend(loc="best", fontsize=8)
        a.grid(True, alpha=0.3)
    ax[0].set_title(f"Min-energy slew (J = {opt.objective:.4f} N$^2$ s) on the full model: open loop vs TV-LQR")
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    print("figure:", out)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "slew_tvlqr.png")
