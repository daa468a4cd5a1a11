"""What the estimation engine fits: the base class of a problem.

A problem hands the engine its tests, its residual groups (log ratios,
model over measured), the noise covariate of each residual and its
candidate causes (objects with ``name``, ``params``
(:class:`rocklab.diagnosis.parameters.Param`) and ``replaces``); the engine
knows nothing of walls.
"""

import numpy as np


class Problem:
    """A set of tests and the residual groups of models over them.

    Subclasses set ``causes`` (the candidates, in the order they are
    reported when tied, each with ``name``, ``params`` and ``replaces``) and
    define :meth:`residuals` (group -> (tests, k) arrays for a subset made by
    :meth:`subset`), :meth:`noise`, :meth:`starts` (data-driven starting
    values) and, optionally, :meth:`heldout_measures` and :meth:`covariates`.
    """

    n_tests: int
    causes: tuple = ()

    def subset(self, idx):
        raise NotImplementedError

    def residuals(self, sub, ext, values):
        raise NotImplementedError

    def candidates(self, families=False):
        """Names of the candidate causes (the listed ones; with ``families``, the generalised families too)."""
        return [c.name for c in self.causes if families or not getattr(c, "family", None)]

    def starts(self, ext):
        return {}

    def heldout_measures(self, sub, ext, values):
        return {}

    def covariates(self, sub):
        """Group -> {label: array like its residuals} for the structure tests."""
        return {}

    def noise(self, sub):
        """Noise covariate (threshold over amplitude) of every residual of :meth:`residuals`."""
        raise NotImplementedError

    def extra_structure(self, sub, ext, values):
        """Structure outside the residual groups (list of statements)."""
        return []

    def form_structure(self, ext):
        """Fit-free evidence that a cause of ``ext`` has the wrong form (list of statements)."""
        return []

    def resolution(self, x):
        """Typical resolution [log units] of a group from its noise covariates ``x``."""
        return float(np.median(x))

    def params(self, ext):
        """The :class:`~rocklab.diagnosis.parameters.Param` of the causes ``ext`` this problem can see, in order."""
        return [q for c in self.causes if c.name in ext for q in c.params]

    def combine(self, current, eff):
        """The causes ``current`` plus ``eff`` in catalogue order, less those ``eff``
        replaces; None where a cause of ``current`` replaces ``eff``."""
        by_name = {c.name: c for c in self.causes}
        if any(eff in by_name[c].replaces for c in current):
            return None
        new = (set(current) | {eff}) - set(by_name[eff].replaces)
        return tuple(c.name for c in self.causes if c.name in new)
