"""The quick start's closing table, from the summary.json files of scripts/paper.sh's runs
(standard library only).  python3 scripts/workbench_table.py RESULTS_DIR"""
import json
import pathlib
import sys

results = pathlib.Path(sys.argv[1])


def summary(name):
    return json.loads((results / name / "summary.json").read_text())


rows = []
for name in ("paper_table1", "paper_force_pulse", "paper_moment_pulse"):
    s = summary(name)
    figures = [f for f in s["files"] if f.endswith(".png") or f.startswith("table")]
    rows.append((f"paper: {name}", s["status"] + "; " + ", ".join(figures), f"{results / name}/"))
s = summary("suppress_slew")
m = s["studies"]["maneuver"]
rows.append(("slew optimum (min energy)",
             f"J = {m['objective']:.4f} N^2 s in {m['duration_s']:g} s ({m['status']}, {m['iterations']} Ipopt iterations"
             + (f" after {m['coarse_start_iterations']} on the coarse mesh)" if m.get('coarse_start_iterations') else ")"),
             f"{results / 'suppress_slew'}/trajectory.csv"))
cases = {(c["case"], c["model"]): c for c in s["studies"]["suppression"]["cases"]}
for case, label in (("open_loop", "open loop"), ("tvlqr", "under TV-LQR")):
    c = cases[(case, "nonlinear")]
    rows.append((f"residual vibration, {label}",
                 f"E_vib = {c['residual_vibration_energy_J']:.3e} J at {s['studies']['suppression']['horizon_s']:g} s,"
                 f" peak tip {c['peak_tip_deflection_m']:.4f} m (full model)",
                 f"{results / 'suppress_slew'}/comparison.csv"))
rows.append(("controller export", "K(t), u_ff(t), x0, u0, A, B, g, poles, histories",
             f"{results / 'suppress_slew'}/controller.mat, controller_*.csv"))
w = [max(len(r[i]) for r in rows) for i in range(2)]
print(f"{'what':<{w[0]}}  {'result':<{w[1]}}  files")
for r in rows:
    print(f"{r[0]:<{w[0]}}  {r[1]:<{w[1]}}  {r[2]}")
