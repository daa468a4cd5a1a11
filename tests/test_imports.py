"""Imports: no cycle among the modules of src/rocklab; what a job that only reads the catalogue pays
(deferred imports, rocklab._imports)."""

from __future__ import annotations

import ast
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import rocklab
from rocklab._imports import lazy_module


def _modules(root):
    """Module name -> source path of every module of the package at ``root``."""
    out = {}
    for f in root.rglob("*.py"):
        parts = f.relative_to(root.parent).with_suffix("").parts
        out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = f
    return out


def import_graph(root):
    """Module -> the package's modules it imports, at module level or inside a function.

    ``from a.b import c`` is an import of ``a.b.c`` where that is a module,
    else of ``a.b``; a name outside the package is left out, and so is the
    implicit import of a module's parent packages.
    """
    modules = _modules(root)

    def owner(name):
        while name and name not in modules:
            name = name.rpartition(".")[0]
        return name or None

    graph = {}
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        targets = set()
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                targets |= {owner(a.name) for a in node.names}
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    up = package.split(".")[: len(package.split(".")) - node.level + 1]
                    base = ".".join([*up, base] if base else up)
                targets |= {f"{base}.{a.name}" if f"{base}.{a.name}" in modules else owner(base) for a in node.names}
        graph[name] = targets - {None, name}
    return graph


def cycles(graph):
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            part = []
            while not part or part[-1] != v:
                part.append(stack.pop())
                on.discard(part[-1])
            if len(part) > 1:
                out.append(sorted(part))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_module_of_rocklab_imports_itself_through_others():
    assert cycles(import_graph(Path(rocklab.__file__).parent)) == []


def package_graph(graph, root):
    """Package -> the packages it imports: each subpackage of ``root`` (all its modules, at any
    depth) and each top-level module is one node; imports within a node are left out."""

    def node(module):
        return ".".join(module.split(".")[:2])

    out = {}
    for module, targets in graph.items():
        out.setdefault(node(module), set()).update(node(t) for t in targets)
    out.pop(root, None)
    return {k: v - {k, root} for k, v in out.items()}


def test_no_package_of_rocklab_imports_itself_through_others():
    """Issue 40, item 4: module-level and function-level imports alike; the statistics the
    diagnosis and the dissipation share are rocklab.inference, below both."""
    graph = package_graph(import_graph(Path(rocklab.__file__).parent), "rocklab")
    assert cycles(graph) == []
    assert "rocklab.dissipation" not in graph["rocklab.diagnosis"]
    assert not {"rocklab.diagnosis", "rocklab.dissipation"} & graph["rocklab.inference"]


def test_the_package_walker_sees_a_cycle_through_a_function_level_import(tmp_path):
    pkg = tmp_path / "pkg"
    for sub in ("one", "two"):
        (pkg / sub / "deep").mkdir(parents=True)
        (pkg / sub / "__init__.py").write_text("")
        (pkg / sub / "deep" / "__init__.py").write_text("")
    (pkg / "__init__.py").write_text("")
    (pkg / "one" / "deep" / "a.py").write_text("from pkg.two import b\n")
    (pkg / "two" / "b.py").write_text("def f():\n    from pkg.one.deep import c\n")
    (pkg / "one" / "deep" / "c.py").write_text("")
    assert cycles(import_graph(pkg)) == []  # no cycle between modules
    assert cycles(package_graph(import_graph(pkg), "pkg")) == [["pkg.one", "pkg.two"]]


def test_no_two_library_modules_share_a_name():
    """Issue 40, item 5: a module's file name is its own, and no package's; only ``__init__.py`` and
    the ``plots/`` modules, each named after the topic it draws, repeat one."""
    root = Path(rocklab.__file__).parent
    names = {}
    for path in root.rglob("*.py"):
        if path.name != "__init__.py" and path.parent.name != "plots":
            names.setdefault(path.stem, []).append(str(path.relative_to(root)))
    for path in root.rglob("__init__.py"):
        if path.parent != root:
            names.setdefault(path.parent.name, []).append(str(path.parent.relative_to(root)) + "/")
    assert {k: v for k, v in names.items() if len(v) > 1} == {}
    assert {p.stem for p in (root / "plots").glob("*.py") if p.name != "__init__.py"} <= set(names)


def test_the_walker_sees_an_import_inside_a_function(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from pkg.sub import b\n")
    (pkg / "sub" / "b.py").write_text("def f():\n    from .. import a\n")
    (pkg / "c.py").write_text("import pkg.a\n")
    assert cycles(import_graph(pkg)) == [["pkg.a", "pkg.sub.b"]]


def _run(code):
    """Run ``code`` in a fresh interpreter (nothing imported yet) and return its stdout."""
    out = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, check=True)
    return out.stdout.strip()


def test_the_catalogue_and_the_calibrated_walls_load_no_scipy_until_used():
    # what Snakemake's own process and the calibrated map jobs import
    out = _run(
        """
        import sys
        from rocklab.diagnosis.catalogue import CAUSES, by_name
        from rocklab.seismic import calibrated
        from rocklab.simulation.reference import simulate_free
        params = {q.name for c in CAUSES for q in by_name(c.name).params}
        heavy = ["scipy.stats._stats_py", "scipy.optimize._optimize", "scipy.signal._savitzky_golay",
                 "scipy.integrate._ivp"]
        print(sorted(m for m in heavy if m in sys.modules), len(params) > 0)
        """
    )
    assert out == "[] True"


def test_a_lazy_module_loads_on_first_use_and_is_the_imported_one():
    out = _run(
        """
        import sys
        from rocklab._imports import lazy_module
        stats = lazy_module("scipy.stats")
        before = "scipy.stats._stats_py" in sys.modules
        value = stats.norm.ppf(0.975)
        import scipy.stats
        from scipy.stats import norm
        print(before, "scipy.stats._stats_py" in sys.modules, round(value, 4), scipy.stats is stats, norm is stats.norm)
        """
    )
    assert out == "False True 1.96 True True"


def test_a_module_already_imported_is_returned_as_it_is():
    assert lazy_module("numpy") is np


def test_a_missing_module_is_named():
    with pytest.raises(ModuleNotFoundError, match="no_such_module"):
        lazy_module("no_such_module")
