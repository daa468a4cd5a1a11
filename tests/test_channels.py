"""Channel health: each injected fault is found, repairable ones are repaired."""

import numpy as np
import pytest

from rocklab.lab.channels import assess_channels, find_spikes, noise_sigma

FS = 400.0


def _record(seed=0, n=4000):
    """Five channels of a decaying oscillation with 3-decimal noisy readings (mm)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / FS
    motion = 80 * np.exp(-t / 3) * np.cos(2 * np.pi * 1.2 * t)
    gains = np.array([0.4, 1.0, 0.4, 1.0, 0.12])
    x = motion[:, None] * gains + rng.normal(0, 0.003, (n, 5))
    return t, np.round(x, 3), motion[:, None] * gains


def test_clean_record_is_untouched():
    _, x, _ = _record()
    y, reps = assess_channels(x, FS, range(5))
    assert [r.status for r in reps] == ["ok"] * 5
    np.testing.assert_array_equal(y, x)


def test_noise_estimate_ignores_the_motion():
    _, x, _ = _record()
    assert noise_sigma(x[:, 1]) == pytest.approx(0.003, rel=0.25)


def test_each_fault_is_classified():
    t, x, _ = _record()
    x[:, 0] = np.round(np.random.default_rng(1).normal(0, 0.004, len(t)), 3)  # dead
    x[1500:, 1] = x[1500, 1]  # stuck to the end
    x[:, 2] = np.minimum(x[:, 2], 20.0)  # clipped at +20 mm
    x[800:1400, 4] = np.nan  # 1.5 s dropout
    _, reps = assess_channels(x, FS, range(5))
    status = {r.channel: r.status for r in reps}
    assert status == {0: "dead", 1: "stuck", 2: "clipped", 3: "ok", 4: "dropout"}
    assert reps[1].lost_from_s == pytest.approx(1500 / FS)


def test_spikes_and_short_gaps_are_repaired():
    t, x, truth = _record()
    x[1000, 1] += 28.0
    x[2500, 3] -= 5.0
    x[3000:3010, 0] = np.nan  # 25 ms gap
    y, reps = assess_channels(x, FS, range(5))
    assert reps[1].spikes == 1 and reps[3].spikes == 1 and reps[0].gap_samples_filled == 10
    assert all(r.status in ("ok", "repaired") for r in reps)
    assert np.abs(y[1000, 1] - truth[1000, 1]) < 0.05
    assert np.nanmax(np.abs(y[3000:3010, 0] - truth[3000:3010, 0])) < 0.05


def test_impact_corner_is_not_a_spike():
    """A V-shaped rebound (one-sided impact) has one large second difference but is real."""
    t = np.arange(2000) / FS
    x = 40 * np.abs(np.sin(2 * np.pi * 0.8 * t))
    assert find_spikes(x, 0.003).size == 0
