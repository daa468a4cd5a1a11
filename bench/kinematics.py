"""Benchmark: batched kinematics solver against a per-time-step scipy loop.

    python bench/kinematics.py --out results/bench [--campaign DIR]

Both solve the same records (a real campaign record when the campaign is
found, else a synthetic rocking record) with the same channels; the loop
calls ``scipy.optimize.least_squares`` once per time step with the analytic
Jacobian.  Writes ``<out>/kinematics.json`` with both times, their ratio and
the largest difference of the answers, and prints the ratio.  With
``--campaign`` (default: the embedded campaign ``raw/campaign``) it also times
the batched solver on every record of the campaign.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.optimize import least_squares

from rocklab.lab.kinematics import _pose, rest_length, solve_wall_motion

DEFAULT_CAMPAIGN = Path(__file__).resolve().parents[1] / "raw" / "campaign"
XYZ_WALL = ["wall_x_mm", "wall_y_mm", "wall_z_mm"]
XYZ_FRAME = ["frame_x_mm", "frame_y_mm", "frame_z_mm"]


def load_record(campaign, row, setups, specimens):
    rec = pd.read_csv(campaign / row.file, comment="#")
    chans = [int(c[2:]) for c in rec.columns[1:]]
    g = setups[setups.setup == row.setup].set_index("channel").loc[chans]
    b = float(specimens.loc[row.specimen, "thickness_mm"])
    return (rec.iloc[:, 1:].to_numpy(float), g[XYZ_WALL].to_numpy(float), g[XYZ_FRAME].to_numpy(float), b, chans)


def scipy_loop(E, X, F, b, x0):
    """One least_squares call per time step (Levenberg-Marquardt, analytic jac)."""
    L0 = rest_length(X, F)
    out = np.full((len(E), 4), np.nan)
    for k, e in enumerate(E):
        target = e + L0

        def fun(q, target=target):
            return _pose(q[:1], q[1:2], q[2:3], q[3:4], X, F, b, False)[0][0] - target

        def jac(q):
            return np.column_stack([d[0] for d in _pose(q[:1], q[1:2], q[2:3], q[3:4], X, F, b, True)[1]])

        out[k] = least_squares(fun, x0[k], jac=jac, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15).x
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("results/bench"))
    ap.add_argument("--campaign", type=Path, default=DEFAULT_CAMPAIGN)
    ap.add_argument("--test", default="T0001", help="record used for the comparison")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    campaign = args.campaign.resolve()
    have_campaign = (campaign / "tests.csv").exists()
    used = [0, 1, 3, 4]

    if have_campaign:
        tests = pd.read_csv(campaign / "tests.csv", dtype=str, keep_default_na=False)
        setups = pd.read_csv(campaign / "setups.csv", dtype={"setup": str})
        specimens = pd.read_csv(campaign / "specimens.csv", dtype={"specimen": str}).set_index("specimen")
        row = tests.set_index("test_id").loc[args.test]
        E, X, F, b, chans = load_record(campaign, row, setups, specimens)
        idx = [chans.index(c) for c in used]
        E, X, F = E[:, idx], X[idx], F[:, :][idx]
        source = f"{campaign.name}/{row.file}"
    else:
        from rocklab.lab.kinematics import transducer_elongation

        X = np.array([[-710, 0, 382], [-710, 0, 926], [710, 0, 926], [710, 0, 654]], float)
        F = np.array([[-710, -180, 382], [-710, -210, 926], [710, -205, 926], [860, 0, 654]], float)
        b = 113.0
        t = np.arange(0, 15, 1 / 400)
        th = 0.1 * np.exp(-0.3 * t) * np.cos(2 * np.pi * t)
        E = transducer_elongation(th, 1e-3 * np.sin(t), 0.5 * np.sin(3 * t), np.cos(t), X, F, b)
        source = "synthetic"
    E = np.round(E, 3)

    best = np.inf
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        sol = solve_wall_motion(E, X, F, b)
        best = min(best, time.perf_counter() - t0)
    q_batch = np.column_stack([sol[k] for k in ("theta", "phi", "v", "w")])

    # Same starting point for the loop as the batched solver's own guess
    # would be, so the comparison times the iterations, not the guess.
    x0 = np.column_stack([np.arctan(E[:, 1] / X[1, 2]), np.zeros((len(E), 3))])
    t0 = time.perf_counter()
    q_loop = scipy_loop(E, X, F, b, x0)
    t_loop = time.perf_counter() - t0
    diff = np.abs(q_batch - q_loop)
    result = {
        "record": source,
        "channels": used,
        "n_steps": int(len(E)),
        "batched_s": best,
        "scipy_loop_s": t_loop,
        "ratio": t_loop / best,
        "max_abs_diff_theta_rad": float(np.nanmax(diff[:, 0])),
        "max_abs_diff_phi_rad": float(np.nanmax(diff[:, 1])),
        "max_abs_diff_v_mm": float(np.nanmax(diff[:, 2])),
        "max_abs_diff_w_mm": float(np.nanmax(diff[:, 3])),
        "batched_all_converged": bool(sol["converged"].all()),
    }

    if have_campaign:
        t_read = t_solve = 0.0
        n_steps = 0
        for row in tests.itertuples():
            t0 = time.perf_counter()
            E, X, F, b, chans = load_record(campaign, row, setups, specimens)
            t1 = time.perf_counter()
            w = np.isin(chans, used).astype(float)
            solve_wall_motion(E, X, F, b, weights=w)
            t_solve += time.perf_counter() - t1
            t_read += t1 - t0
            n_steps += len(E)
        result.update(
            campaign_tests=int(len(tests)), campaign_steps=n_steps, campaign_solve_s=t_solve, campaign_read_s=t_read
        )

    (args.out / "kinematics.json").write_text(json.dumps(result, indent=2) + "\n")
    print(
        f"kinematics: batched {best * 1e3:.1f} ms, scipy loop {t_loop:.2f} s on "
        f"{len(q_batch)} steps: ratio {result['ratio']:.0f}x, "
        f"max |dtheta| {result['max_abs_diff_theta_rad']:.1e} rad"
    )
    if have_campaign:
        print(
            f"campaign: {result['campaign_tests']} tests, {result['campaign_steps']} steps, "
            f"solve {result['campaign_solve_s']:.1f} s (+ read {result['campaign_read_s']:.1f} s)"
        )
    return result


if __name__ == "__main__":
    main()
