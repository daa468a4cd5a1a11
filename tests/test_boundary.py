"""rocklab.physics.boundary: one name per boundary condition, read and written as the lab's words."""

import json

import numpy as np
import pandas as pd

from rocklab.physics import restitution
from rocklab.physics.boundary import Boundary


def test_a_boundary_is_the_name_the_files_use():
    assert list(Boundary) == ["two-sided", "one-sided"]
    assert Boundary("one-sided") is Boundary.ONE_SIDED
    assert json.dumps({Boundary.TWO_SIDED: Boundary.ONE_SIDED}) == '{"two-sided": "one-sided"}'
    assert f"{Boundary.TWO_SIDED}" == "two-sided" and {"two-sided": 1}[Boundary.TWO_SIDED] == 1
    assert [b.key for b in Boundary] == ["two_sided", "one_sided"]
    assert [b.short for b in Boundary] == ["2s", "1s"]


def test_a_column_of_names_compares_with_a_boundary():
    column = pd.Series(["one-sided", "two-sided", "one-sided"])
    assert (column == Boundary.ONE_SIDED).tolist() == [True, False, True]
    names = np.array(["two-sided", "one-sided"])
    np.testing.assert_allclose(
        restitution.analytic(names, 0.1), [restitution.two_sided(0.1), restitution.one_sided(0.1)]
    )
