"""Restitution diagnosis of block tests: hidden effects in synthetic ratios, and the UMinho limestone blocks."""

import numpy as np
import pandas as pd
import pytest

from rocklab.diagnosis import block_tests as B
from rocklab.physics import restitution


def synthetic_events(
    c=1.0, s_e=0.0, b=0.0, noise=0.02, n_trials=12, groups=(4, 8, 12), seed=0, loss_fraction=1.0, loss_constant=0.0
):
    """Per-impact ratios like the limestone tables: e = c e_an exp(+-s_e/2) (1 - b u), lognormal noise
    growing as the impact speed falls; e_an = 1 - lambda (1 - e_Housner) - delta (1 and 0: Eq. 2)."""
    rng = np.random.default_rng(seed)
    rows = []
    for g, hb in enumerate(groups, start=1):
        B_m, H_m = 0.05, 0.05 * hb
        e_an = 1.0 - loss_fraction * (1.0 - float(restitution.two_sided(np.arctan2(B_m, H_m)))) - loss_constant
        for trial in range(1, n_trials + 1):
            u = 1.0
            for k in range(1, 16):
                e = c * e_an * np.exp((0.5 if k % 2 else -0.5) * s_e) * (1.0 - b * u)
                r = e * np.exp(rng.normal(0.0, noise / np.sqrt(u)))
                rows.append((g, trial, k, np.nan, B_m, H_m, r))
                u *= r**2
    return pd.DataFrame(
        rows, columns=["group", "trial", "event", "duplicate_of", "B_m", "H_m", "measured_source_angular_ratio"]
    ).assign(alpha=lambda d: np.arctan2(d.B_m, d.H_m))


@pytest.mark.parametrize(
    "kw, effect, truth",
    [
        ({}, None, {}),
        ({"c": 0.96}, "restitution_scale", {"c": 0.96}),
        ({"s_e": 0.06}, "hinge_asymmetry", {"s_e": 0.06}),
        ({"c": 1.02, "b": 0.06}, "restitution_amplitude", {"b": 1.02 * 0.06}),
    ],
)
def test_hidden_restitution_effects_in_block_ratios(kw, effect, truth):
    e = B.diagnose_blocks(synthetic_events(**kw), n_boot=20).all
    assert e.verdict == ([effect] if effect else []) and not e.unexplained, (e.verdict, e.rejected)
    for f in e.findings:
        for k, x in truth.items():
            lo, hi = f.ci95[k]
            assert lo - 0.1 * abs(x) <= x <= hi + 0.1 * abs(x), (k, x, f.params[k], (lo, hi))
        assert f.gain["deviance_per_obs"] > 0


def test_limestone_blocks():
    ev = B.read_events()
    assert len(ev) == 7519 and ev.groupby(["group", "trial"]).ngroups == 134
    res = B.diagnose_blocks(ev, n_boot=10)
    assert len(res.groups) == 12
    a = res.all
    assert a.n_tests == 134 and a.verdict == []
    # the stockiest blocks lose less, the slenderest more; but slenderness varies between 12 block groups,
    # not 134 trials: over the group means the trend has p = 0.016 (4.5e-5 over trials), short of the
    # signature's 1 % gate, and the structure tests at group level find no trend left
    st = res.slenderness
    assert st["slope"] > 0 and st["n_groups"] == 12 and st["n_trials"] == 134
    assert 0.01 < st["p"] < 0.03
    assert not a.residual_structure and not a.unexplained
    # the family affine in Housner's loss, folds and resamples by block group: about half to nine tenths of
    # Housner's loss plus ~2 % per impact, no closed form of the library, its held-out gain within the noise
    (fam,) = a.families
    lam, delta = fam.ci95["loss_fraction"], fam.ci95["loss_constant"]
    assert lam[1] < 1.0 and 0.005 < delta[0] and delta[1] < 0.05, fam
    assert fam.reduces_to == "no closed form of the library" and fam.dbic_vs_base < -10
    assert not fam.discovered and not a.weak_evidence
    assert B.blocks_markdown(res).startswith("# Restitution of the UMinho limestone blocks")


def test_the_pooled_blocks_are_resampled_by_block_group():
    """Slenderness varies between block groups: the pooled problem's units (its folds, its resamples) are
    the groups, each with every impact of its trials."""
    trials = B.pooled(B.group_trials(synthetic_events(groups=(4, 8, 12), n_trials=5)))
    rows = B.by_group(trials)
    assert len(rows.ids) == 3 and rows.r.shape == (3, 5 * B.N_IMPACTS)
    assert np.isfinite(rows.r).sum() == np.isfinite(trials.r).sum()
    assert np.allclose(np.sort(rows.r[np.isfinite(rows.r)]), np.sort(trials.r[np.isfinite(trials.r)]))
    assert B.BlockProblem(rows).n_tests == 3


@pytest.mark.parametrize(
    "loss_fraction, loss_constant, noise", [(0.6, 0.02, 0.02), (0.6, 0.02, 0.01), (0.8, 0.01, 0.01)]
)
def test_an_impact_law_affine_in_housners_loss_is_discovered(loss_fraction, loss_constant, noise):
    ev = synthetic_events(
        loss_fraction=loss_fraction, loss_constant=loss_constant, noise=noise, groups=(4, 6, 8, 10, 12, 15), n_trials=15
    )
    a = B.diagnose_blocks(ev, n_boot=20).all
    assert a.verdict == ["restitution_housner_loss"] and not a.unexplained, (a.verdict, a.rejected)
    (f,) = a.findings
    assert f.discovered and f.reduces_to == "no closed form of the library"
    for k, x in (("loss_fraction", loss_fraction), ("loss_constant", loss_constant)):
        lo, hi = f.ci95[k]
        assert lo - 0.1 * abs(x) <= x <= hi + 0.1 * abs(x), (k, x, f.params[k], (lo, hi))
    assert f.heldout_gain["vs_base"] > 2 * f.heldout_gain["vs_base_se"]
    assert a.families[0].discovered


def test_a_subtle_housner_loss_on_six_block_groups_is_named_at_group_level():
    """A fifth of Housner's loss removed and 1 % per impact added, at the noise of the limestone tables.

    Fifteen trials in each of six groups, each decaying at its own rate, make
    the ratios pooled over them change with u = (thetadot_k/thetadot_1)^2 (a
    trial or a group that loses more reaches small u sooner); within trials
    nothing changes with u.  The amplitude law's signature is taken within trials and
    is absent, so it cannot take the effect, and the loss across the six
    slendernesses is named with the truth inside its intervals, its held-out
    gain over the block groups left out in turn beyond the noise."""
    ev = synthetic_events(loss_fraction=0.8, loss_constant=0.01, noise=0.02, groups=(4, 6, 8, 10, 12, 15), n_trials=15)
    a = B.diagnose_blocks(ev, n_boot=20).all
    assert a.rejected["restitution_amplitude"] == "its signature in the data is absent"
    assert a.verdict == ["restitution_housner_loss"] and not a.unexplained, (a.verdict, a.rejected)
    (f,) = a.findings
    for k, x in (("loss_fraction", 0.8), ("loss_constant", 0.01)):
        lo, hi = f.ci95[k]
        assert lo <= x <= hi, (k, x, f.params[k], (lo, hi))
    assert f.heldout_gain["vs_base"] > 2 * f.heldout_gain["vs_base_se"]
