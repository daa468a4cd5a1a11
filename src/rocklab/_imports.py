"""Deferred imports of the heavy scientific modules.

Every job of the workflow is a Python process of its own, and importing
scipy.stats, scipy.optimize or scipy.integrate costs 0.5-1.5 s of CPU
(scipy 1.17 rewrites the docstring of every public function as it loads).
The diagnosis' catalogue of causes is imported by jobs that only read the
names and parameters of the causes (the calibrated maps, Snakemake's own
process after the diagnosis checkpoint); a module that needs scipy in a
function only binds the module at import, and loads it on first use.
"""

from __future__ import annotations

import importlib.util
import sys
from types import ModuleType


def lazy_module(name: str) -> ModuleType:
    """The module ``name``, loaded when one of its attributes is first read.

    An already imported module is returned as it is.  Parents are imported
    now (``scipy`` for ``scipy.stats``: light); the module itself is put in
    ``sys.modules``, so a later ``import`` of it finds the same object
    (``importlib.util.LazyLoader``, whose first load is not thread-safe in
    Python 3.11, python/cpython#114763: rocklab starts no Python threads).

    Raises
    ------
    ModuleNotFoundError
        When there is no such module.
    """
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.find_spec(name)
    if spec is None:
        raise ModuleNotFoundError(f"No module named {name!r}", name=name)
    if spec.loader is None:  # LazyLoader needs a loader to wrap (a namespace package has one since 3.11)
        raise ImportError(f"module {name!r} has no loader", name=name)
    loader = importlib.util.LazyLoader(spec.loader)
    spec.loader = loader
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    loader.exec_module(module)
    return module
