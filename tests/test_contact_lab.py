"""The contact lab (rocklab.lab.contact_lab): a rigid block on compliant contacts, integrated by MuJoCo,
checked against Housner's Eq. 1-2, its energy, the lab's readers and itself."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

pytest.importorskip("mujoco")

from rocklab.dissipation.analysis import analyse_reduced_test
from rocklab.lab import contact_lab as cl
from rocklab.lab import virtual_lab as vl
from rocklab.lab.campaign import open_campaign
from rocklab.lab.reduction import reduce_test
from rocklab.physics import restitution, wall

SPECIMENS = vl.DEFAULT_SPECIMENS.set_index("specimen")


def _block(specimen):
    sp = SPECIMENS.loc[specimen]
    return sp.height_mm / 1e3, sp.thickness_mm / 1e3


def test_importing_rocklab_and_the_contact_lab_loads_no_mujoco():
    code = """
        import sys
        import rocklab
        from rocklab.lab import contact_lab, virtual_lab
        print("mujoco" in sys.modules, contact_lab.ContactModel().mu)
        """
    out = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "0.8"]


@pytest.mark.parametrize("specimen", ["2a", "1a", "5c"])
def test_a_stiff_critically_damped_contact_gives_housners_restitution(specimen):
    """Independent check: nothing in the block says what an impact loses, yet a stiff contact that does not
    bounce (t_c = 0.5 ms, damping ratio 1, near-sharp edges) loses what Eq. 2 says, within 3 % of Housner's
    loss 1 - e_an (h/b 14.4, 9.6 and 6.5)."""
    h, b = _block(specimen)
    model = cl.ContactModel(contact_time_s=5e-4, edge_radius_mm=0.05)
    hist = cl.simulate_contact(h, b, 0.9 * cl.rocking_angle(h, b, model), model=model, t_end=3.0)
    ep = cl.contact_episodes(hist)
    e_an = restitution.two_sided(wall.slenderness_angle(h, b))
    assert len(ep) >= 2
    assert ep.slip_mm.abs().max() < 0.01
    assert np.abs((1 - ep.e) / (1 - e_an) - 1).max() < 0.03


def test_the_energy_does_not_rise_between_impacts_without_damping_in_flight():
    """With zeta = 0 the block's energy never rises in a flight by more than 1 % of the next impact's loss
    (the contact's spring stores and gives back a little), and a flight loses under 10 % of what an impact
    does (the pivot's damper works as the load on it changes); with zeta = 0.02 a flight loses more."""

    def flights(zeta):
        h, b = _block("5c")
        model = cl.ContactModel(zeta=zeta)
        hist = cl.simulate_contact(h, b, 0.95 * cl.rocking_angle(h, b, model), model=model, t_end=4.0)
        ep = cl.contact_episodes(hist)
        start, end = (np.searchsorted(hist.t, ep[c]) for c in ("t_start", "t_end"))
        E = hist.energy
        spans = list(zip(np.r_[0, end[:-1]], start))
        rise = [np.max(E[a : c + 1] - np.minimum.accumulate(E[a : c + 1])) for a, c in spans]
        return np.array(rise), np.array([E[a] - E[c] for a, c in spans]), E[start] - E[end]

    rise, drop, loss = flights(0.0)
    assert len(loss) >= 4 and (loss > 0).all()
    assert (rise < 0.01 * loss).all()
    assert (drop > -0.01 * loss).all() and (drop < 0.1 * loss).all()
    _, drop_damped, loss_damped = flights(0.02)
    assert (drop_damped[1:] > 0.3 * loss_damped[1:]).all()


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    """A free-standing wall 5c released at 0.95 of its rocking angle, written by the contact lab in the lab's
    format (400 Hz transducers, every effect of the campaign on) and reduced by rocklab.lab.reduction."""
    folder = tmp_path_factory.mktemp("contact") / "campaign"
    plan = [vl.VirtualTest("C0001", "5c", theta0_ratio=0.95)]
    truth = vl.write_campaign(folder, plan, seed=3, t_end=30.0, simulate=cl.simulate_contact_test)
    # the truth's impacts: the same test and stream again (the physics is deterministic)
    sp = SPECIMENS.loc["5c"]
    layout = pd.read_csv(folder / "setups.csv")
    rng = np.random.default_rng(np.random.SeedSequence(3).spawn(1)[0])
    _, _, full = cl.simulate_contact_test(plan[0], sp, layout, rng, 30.0)
    ds = reduce_test(open_campaign(folder), "C0001")
    return folder, truth.iloc[0], full, ds


def test_a_written_test_reads_back_with_each_impacts_e_as_measured(campaign):
    """Each impact the reduction finds above a tenth of alpha is one of the block's contact episodes (within a
    sample), and its e (thetadot^+ / thetadot^- of rocklab.lab.motion's flight fits) is the e measured
    across that episode within 0.003 (0.0015 in the median)."""
    folder, truth, full, ds = campaign
    assert truth.generator == "contact_lab" and truth.expected_reason == "valid"
    assert ds.attrs.get("reject_reason", "") in ("", "valid")
    _, imp, _ = analyse_reduced_test(ds)
    imp = imp[imp.peak_before_over_alpha > 0.1]
    true = full["impacts"]
    assert len(imp) >= 20
    j = np.abs(imp.t_s.to_numpy()[:, None] - true.t.to_numpy()[None, :]).argmin(axis=1)
    assert np.abs(imp.t_s.to_numpy() - true.t.to_numpy()[j]).max() < 1.5 / 400
    diff = (imp.thetadot_after / imp.thetadot_before).to_numpy() - true.e.to_numpy()[j]
    assert np.median(np.abs(diff)) < 0.0015 and np.abs(diff).max() < 0.003
    # and the truth is Housner's within 5 % of the loss, the contact being stiff (2 ms) and not bouncing
    assert truth.restitution_scale == pytest.approx(1.0, abs=0.05 * (1 - truth.e_housner_block))


def test_the_same_seed_writes_the_same_bytes(tmp_path):
    plan = [vl.VirtualTest("C0001", "1a", theta0_ratio=0.9, model={"contact_time_s": 0.004})]
    files = {}
    for run, seed in (("a", 5), ("b", 5), ("c", 6)):
        vl.write_campaign(tmp_path / run, plan, seed=seed, t_end=3.0, simulate=cl.simulate_contact_test)
        files[run] = [(tmp_path / run / f).read_bytes() for f in ("tests/C0001.csv.gz", "truth.csv", "tests.csv")]
    assert files["a"] == files["b"]
    assert files["a"][0] != files["c"][0]


def test_the_knobs_act_as_documented():
    """alpha_ratio sets in the edges so that the block rocks on that angle; a soft impedance loses more
    than Housner's e; one-sided walls are refused by name."""
    h, b = _block("1a")
    test = vl.VirtualTest("C", "1a", alpha_ratio=0.9)
    model = cl.contact_model_of(test, h, b)
    assert cl.rocking_angle(h, b, model) == pytest.approx(0.9 * wall.slenderness_angle(h, b))
    assert cl.housner_of_block(h, b, model) > restitution.two_sided(wall.slenderness_angle(h, b))
    soft = cl.ContactModel(impedance=(0.5, 0.9, 0.001))
    hist = cl.simulate_contact(h, b, 0.9 * cl.rocking_angle(h, b, soft), model=soft, t_end=2.5)
    assert cl.contact_episodes(hist).e.iloc[0] < cl.housner_of_block(h, b, soft) - 0.005
    with pytest.raises(ValueError, match="two-sided"):
        sp = SPECIMENS.loc["1a"]
        cl.simulate_contact_test(replace(test, boundary="one-sided", contact_depth_mm=120.0), sp, None, 0)


def test_the_flight_zeta_reads_the_knob_and_the_pivots_own_loss():
    """Wall 1a, 10 s: the knob zeta = 0.01 reads back within 10 %, the pivot's spring-damper adding its own
    small loss; without the knob, that loss alone, positive and under a tenth of the knob's."""
    h, b = _block("1a")
    read = {}
    for zeta in (0.0, 0.01):
        model = cl.ContactModel(zeta=zeta, edge_radius_mm=0.05)
        hist = cl.simulate_contact(h, b, 0.95 * cl.rocking_angle(h, b, model), model=model, t_end=10.0)
        ep = cl.contact_episodes(hist)
        z = cl.flight_zeta(hist, ep, 0.3 * hist.rocking_angle)
        assert z.size >= 5
        read[zeta] = float(np.median(z))
    assert 0.0 < read[0.0] < 1e-3
    assert read[0.01] == pytest.approx(0.01 + read[0.0], rel=0.1)
