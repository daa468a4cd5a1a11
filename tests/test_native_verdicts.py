"""The same verdicts whatever the file (issue 43, item 6): one series of wall 1a whose restitution is scaled
by 0.90, written from the same true motions as text transducer records, LabVIEW's TDMS, motion capture's C3D
and a film; each campaign reduced (rocklab.lab.reduction) and diagnosed (rocklab.diagnosis) as the workflow
does. Each names the scale and nothing else, with intervals that meet and hold the truth."""

import numpy as np
import pytest

from rocklab import diagnosis as D
from rocklab.diagnosis.evidence import records_by_series
from rocklab.lab.campaign import open_campaign
from rocklab.lab.reduction import reduce_tests
from rocklab.lab.virtual_lab import VirtualTest, write_campaign
from rocklab.lab.virtual_native import VideoEffects
from rocklab.physics import impact as I

#: The hidden cause: e = 0.90 e_an,2s, named from a few tests (tests/test_diagnosis.py, scale-0.90).
C = 0.90
#: Each format at its instrument's rate [Hz]: the simulator samples the same motion at each (0.1 s a test:
#: text and TDMS sharing theirs saved 0.5 s of 11).
FORMATS = {"transducers": 400.0, "tdms": 400.0, "c3d": 240.0, "video": 60.0}
#: A cheap film that still holds c: 120 x 90 pixels (the wall 100 high, markers 7 across) with the camera's
#: noise, blur, tilt, occlusions and MPEG-4, 5 s of the file's 11.  The cost goes with the frames, hardly with
#: their size; the bench's film (240 frames a second, 480 x 360) costs ten times as much.
FILM = VideoEffects(height_px=120, width_px=90, marker_px=7.0)
#: Seed of the releases and of every effect.
SEED = 1
#: How far the intervals may miss each other and the truth.  They are the spread of c between tests (5e-6 wide
#: from the transducers, 6e-4 from the film), blind to the bias of a reduction: over 14 seeds the film's missed
#: the truth twice, by 4e-5 and 3e-4 (impacts seen 1/60 s apart; at 30 frames a second, 2 of 10 by 3e-4), the
#: transducers' twice by 3e-7 (the solver's).  A fifth of the smallest departure of c from 1 worth naming (its
#: practical margin, 0.005).
TOL = 1e-3


@pytest.fixture(scope="module")
def diagnosed(tmp_path_factory):
    """Six tests of wall 1a in each format, one campaign each, diagnosed as one series.

    Six, not four: with five tests or more a cause that improves every test is named (the sign test of
    rocklab.diagnosis.estimation.selection); of four, C3D at 240 Hz named nothing in one seed of 18.
    """
    theta0 = np.random.default_rng(SEED).uniform(0.97, 0.998, 6)
    out = {}
    for kind, fs in FORMATS.items():
        plan = [
            VirtualTest(
                f"T{i:04d}",
                "1a",
                fs=fs,
                instrument=kind,
                alpha_ratio=1.0,
                theta0_ratio=float(x),
                model={"impact": I.Scaled(I.HousnerTwoSided(), C)},
                video=FILM,
            )
            for i, x in enumerate(theta0)
        ]
        folder = tmp_path_factory.mktemp(kind)
        # one seed: each test's noise drawn alike in every format
        write_campaign(folder, plan, seed=SEED, t_end=60.0)
        reduced = [ds for _, ds in reduce_tests(open_campaign(folder), [t.test_id for t in plan])]
        assert all(ds.attrs["valid"] for ds in reduced), kind
        (records,) = records_by_series(reduced).values()
        out[kind] = D.diagnose_series(records, key=kind, n_boot=10, n_history=0)
    return out


def test_every_format_names_the_hidden_scale_with_intervals_that_meet_and_hold_it(diagnosed):
    assert {kind: d.verdict for kind, d in diagnosed.items()} == {kind: ["restitution_scale"] for kind in FORMATS}
    found = {kind: {f.effect: f for f in d.findings} for kind, d in diagnosed.items()}
    ci = {kind: f["restitution_scale"].ci95["c"] for kind, f in found.items()}
    assert max(lo for lo, _ in ci.values()) <= min(hi for _, hi in ci.values()) + TOL, ci
    assert all(lo - TOL <= C <= hi + TOL for lo, hi in ci.values()), ci
