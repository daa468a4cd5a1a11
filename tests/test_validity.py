"""The lab's validity rules, against closed forms and hand-built cases."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from rocklab.lab.release import release_state
from rocklab.lab.validity import (
    Verdict,
    channel_roles,
    choose_channels,
    residual_out_of_plumb,
    top_displacement,
    verdict,
)


def _usual_setup():
    rows = [
        (0, -710, 0, 382, -710, -180, 382),
        (1, -710, 0, 926, -710, -210, 926),
        (2, 710, 0, 382, 710, -185, 382),
        (3, 710, 0, 926, 710, -205, 926),
        (4, 710, 0, 654, 860, 0, 654),
        (5, 0, 56.5, 500, 0, 216.5, 500),
    ]
    return pd.DataFrame(
        rows, columns=["channel", "wall_x_mm", "wall_y_mm", "wall_z_mm", "frame_x_mm", "frame_y_mm", "frame_z_mm"]
    )


def test_roles_from_geometry():
    roles = channel_roles(_usual_setup(), 113.0)
    assert roles.role.tolist() == ["out_of_plane"] * 4 + ["in_plane", "monitor"]


def test_backup_replaces_one_lost_channel_and_two_reject():
    roles = channel_roles(_usual_setup(), 113.0)
    ok = choose_channels(roles, set())
    assert ok.used == [0, 1, 3, 4] and ok.malfunction is None
    one = choose_channels(roles, {1})
    assert one.used == [0, 2, 3, 4] and "backup ch2 used" in one.flags and one.malfunction is None
    two = choose_channels(roles, {0, 3})
    assert two.malfunction is not None
    v_lost = choose_channels(roles, {4})
    assert not v_lost.solve_v and "in-plane channel lost: v = 0" in v_lost.flags


def test_top_displacement_of_pure_rotation():
    """Rotation theta about the edge y = +b/2: dy_top = h sin(theta) + b/2 (1 - cos(theta))."""
    h, b, L = 1630.0, 113.0, 1440.0
    theta = np.array([0.0, 0.01, 0.05, -0.03])
    top = top_displacement(theta, 0 * theta, 0 * theta, 0 * theta, L, h, b)
    expected = h * np.sin(theta) + np.sign(theta) * b / 2 * (1 - np.cos(theta))
    np.testing.assert_allclose(top[:, 0], expected, atol=1e-6)
    np.testing.assert_allclose(top[:, 1], expected, atol=1e-6)


def test_residual_reads_the_tail():
    top = np.zeros((4000, 2))
    top[-400:] = [1.7, 1.6]
    assert residual_out_of_plumb(top, 400.0) == pytest.approx(1.7)


@pytest.mark.parametrize("kick", [0.0, 0.02, 0.05])
def test_release_velocity_recovered(kick):
    """Fall from theta_h with a given initial velocity, the linearised closed form."""
    p, alpha, fs = 3.3, 0.09, 400.0
    t = np.arange(0, 3.0, 1 / fs)
    hold = t < 1.0
    tau = np.clip(t - 1.0, 0, None)
    th0 = 0.98 * alpha  # held just inside its instability rotation
    theta = alpha + (th0 - alpha) * np.cosh(p * tau) - kick / p * np.sinh(p * tau)
    theta = np.where(hold, th0, theta)
    theta = theta[theta > -0.01]
    theta = theta + np.random.default_rng(0).normal(0, 1e-5, theta.size)
    st = release_state(np.arange(theta.size) / fs, theta, p)
    # within 1 % of the overturning velocity (Eq. 16), a tenth of the lab's 10 % rule
    thetadot_r = p * np.sqrt(2 * (1 - np.cos(alpha)))
    assert st["thetadot0"] == pytest.approx(kick, abs=0.01 * thetadot_r)
    assert st["theta0"] == pytest.approx(th0, abs=0.002 * alpha)
    # a fall from rest leaves its turning point with theta' = 0, so the instant
    # is extrapolated back from the fall and known to about 1/(2p)
    assert st["t_release"] == pytest.approx(1.0, abs=0.5 / p)


def test_verdict_order():
    roles = channel_roles(_usual_setup(), 113.0)
    rules = {"residual_top_mm": 1.5, "release_velocity_ratio": 0.1}
    assert verdict(choose_channels(roles, set()).malfunction, 0.02, 0.5, rules) == (True, "", "")
    assert verdict(choose_channels(roles, set()).malfunction, 0.2, 3.0, rules)[1] == "disturbed_initial_conditions"
    assert verdict(choose_channels(roles, set()).malfunction, 0.02, 1.6, rules)[1] == "residual_out_of_plumb"
    assert verdict(choose_channels(roles, {0, 1}).malfunction, 0.2, 3.0, rules)[1] == "instrument_malfunction"


def test_the_qc_schema_allows_the_verdicts_and_no_other_word():
    """One vocabulary: qc.csv's reject_reason is empty (valid) or a rejection of Verdict."""
    schema = yaml.safe_load(
        (Path(__file__).resolve().parents[1] / "workflow" / "schemas" / "qc.schema.yaml").read_text()
    )
    allowed = set(schema["properties"]["reject_reason"]["enum"]) - {"", None}
    assert allowed == {v.value for v in Verdict.rejections()}
    assert Verdict.VALID not in Verdict.rejections() and Verdict.rejections()[0] == Verdict.UNREADABLE
