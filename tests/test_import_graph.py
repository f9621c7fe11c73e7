"""The package's imports: what the import-linter contracts in pyproject.toml cannot say, and a test that runs them.

The layers, the independent siblings, the CLI's own layers, "no import circle between sibling modules at any
depth" and the third-party packages kept to one layer are import-linter contracts (``[tool.importlinter]`` in
pyproject.toml; ``lint-imports`` from the repository root): :func:`test_the_import_contracts_hold` runs them. Kept
here, what they do not see:

* a circle through a package's own ``__init__`` (``pkg/__init__.py -> pkg.a -> pkg``): the contract that finds
  circles compares a package's children, and its ``__init__`` is none of them;
* an import hidden behind the root package's lazy public names (``import satchain; satchain.run(...)`` imports
  ``satchain.api`` through PEP 562, which no import statement shows);
* that modules split or moved keep every public name at the old path.

The graph is read from the source with ``ast`` (nothing is imported): an edge ``a -> b`` for every import of a
satchain module ``b`` in module ``a`` -- top-level statements, including those under ``if``/``try``/``with``, and
(``deferred=True``) those inside functions, but never those guarded by ``if TYPE_CHECKING`` (as the contracts).
"""

from __future__ import annotations

import ast
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"
PACKAGE = SRC / "satchain"


def _modules() -> dict[str, tuple[Path, bool]]:
    out = {}
    for p in PACKAGE.rglob("*.py"):
        parts = list(p.relative_to(SRC).with_suffix("").parts)
        is_pkg = parts[-1] == "__init__"
        out[".".join(parts[:-1] if is_pkg else parts)] = (p, is_pkg)
    return out


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _executed_imports(body: list[ast.stmt], *, deferred: bool) -> list[ast.Import | ast.ImportFrom]:
    """Import statements run on import (``deferred``: also those inside functions and classes)."""
    out: list[ast.Import | ast.ImportFrom] = []
    for node in body:
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            out.append(node)
        elif isinstance(node, ast.If):
            if not _is_type_checking(node.test):
                out += _executed_imports(node.body, deferred=deferred)
            out += _executed_imports(node.orelse, deferred=deferred)
        elif isinstance(node, ast.Try):
            for block in (node.body, *(h.body for h in node.handlers), node.orelse, node.finalbody):
                out += _executed_imports(block, deferred=deferred)
        elif isinstance(node, ast.With):
            out += _executed_imports(node.body, deferred=deferred)
        elif deferred:
            for child in ast.walk(node):
                if isinstance(child, (ast.Import, ast.ImportFrom)):
                    out.append(child)
    return out


def import_graph(*, deferred: bool = False) -> dict[str, set[str]]:
    """``{module: satchain modules it imports}``; ``from pkg import name`` counts ``pkg.name`` when that is a
    module, else ``pkg``."""
    mods = _modules()
    graph: dict[str, set[str]] = {}
    for name, (path, is_pkg) in mods.items():
        package = name if is_pkg else name.rpartition(".")[0]
        deps: set[str] = set()
        for node in _executed_imports(ast.parse(path.read_text(encoding="utf-8")).body, deferred=deferred):
            if isinstance(node, ast.Import):
                deps |= {a.name for a in node.names if a.name in mods}
                continue
            base = node.module or ""
            if node.level:
                up = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(up + ([node.module] if node.module else []))
            for a in node.names:
                full = f"{base}.{a.name}"
                deps |= {full} if full in mods else ({base} if base in mods else set())
        deps.discard(name)
        graph[name] = deps
    return graph


def cycles(graph: dict[str, set[str]]) -> list[frozenset[str]]:
    """The strongly connected components of more than one module (Tarjan), i.e. the import circles."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[frozenset[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = set()
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.add(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(frozenset(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_the_cycle_finder_finds_circles_and_only_circles():
    g = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a", "e"}, "e": set(), "f": {"f2"}, "f2": {"f"}}
    assert sorted(map(sorted, cycles(g))) == [["a", "b", "c"], ["f", "f2"]]
    assert cycles({"a": {"b"}, "b": {"c"}, "c": set()}) == []


def test_the_graph_sees_relative_absolute_and_conditional_imports():
    g = import_graph()
    assert "satchain.results" in g["satchain.pipeline"]  # from satchain.results import ...
    assert "satchain.errors" in g["satchain"]  # the package __init__
    assert "satchain.api" not in g["satchain"]  # lazy (PEP 562) and TYPE_CHECKING imports do not count
    assert "satchain.pipeline" not in g["satchain.api"]  # deferred into run()
    assert "satchain.pipeline" in import_graph(deferred=True)["satchain.api"]


def test_no_import_circle_even_through_a_package_init():
    # the acyclic_siblings contract compares siblings; this also sees pkg/__init__ -> pkg.a -> pkg
    found = cycles(import_graph(deferred=True))
    assert found == [], sorted(map(sorted, found))


def _root_attributes(tree: ast.Module) -> set[str]:
    """Names read off the root package: ``from satchain import NAME`` and ``satchain.NAME``."""
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module == "satchain" and not node.level:
            out |= {a.name for a in node.names}
        elif isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == "satchain":
            out.add(node.attr)
    return out


def test_below_the_cli_no_module_imports_through_the_root_packages_lazy_names():
    # satchain.NAME of a lazy public name imports its module unseen by import-linter: import it from its home.
    # The CLI, the top layer, may call the public API as a user does (satchain.run).
    import satchain

    lazy = set(satchain._LAZY)
    used = {}
    for name, (path, _) in _modules().items():
        if name != "satchain" and not name.startswith(("satchain.cli", "satchain.__main__")):
            hidden = _root_attributes(ast.parse(path.read_text(encoding="utf-8"))) & lazy
            if hidden:
                used[name] = sorted(hidden)
    assert not used, f"import these from their modules (satchain._LAZY names them): {used}"


def test_the_import_contracts_hold():
    lint = shutil.which("lint-imports", path=str(Path(sys.executable).parent)) or shutil.which("lint-imports")
    if lint is None:
        pytest.skip("import-linter is not installed (pip install import-linter): pyproject's contracts not checked")
    n = (ROOT / "pyproject.toml").read_text(encoding="utf-8").count("[[tool.importlinter.contracts]]")
    env = {**os.environ, "PYTHONPATH": str(SRC)}  # this checkout's package, whatever is installed
    r = subprocess.run([lint, "--no-cache", "--no-logo"], cwd=ROOT, env=env, capture_output=True, text=True,
                       timeout=300)  # fmt: skip
    assert r.returncode == 0, r.stdout[-6000:] + r.stderr[-2000:]
    assert f"Contracts: {n} kept, 0 broken." in r.stdout, r.stdout[-2000:]


# ------------------------------------------------------------------------------- split modules keep their names

#: Public names of modules that were split (issue 18): importable from the old path, forever.
OLD_NAMES = {
    "satchain.radiometry": (
        "AU_M C_M_PER_S GIQE_REFLECTANCES H_J_S K_J_PER_K NoiseBudget RadiometryResult SIGMA_W_PER_M2_K4 "
        "SOLAR_SPECTRA SUN_RADIUS_M atmosphere_transmissions band_radiance contrast_snr electrons_per_pixel "
        "focal_plane_irradiance lambertian_radiance noise_budget photon_radiance planck_solar_irradiance "
        "planck_spectral_radiance radiometric_budget signal_electrons snr_vs_reflectance solar_spectrum "
        "spectral_per_m_to_per_um spectral_per_um_to_per_m surface_irradiance toa_radiance"
    ),
    "satchain.tf.optics": (
        "SHANNON_W0_WAVES DiffractionOTF PupilOTF PupilPSF PupilParams annular_mtf diffraction_otf "
        "make_diffraction_otf noll_to_nm optical_cutoff_cy_per_mm pupil_otf pupil_psf shannon_atf zernike_noll"
    ),
    "satchain.api": "BudgetResult Measurements RunResult SceneResult SimulationResult strict_json as_run_config run",
}
PARTS = {
    "satchain.radiometry": ("source", "focal_plane", "noise", "budget"),
    "satchain.tf.optics": ("satchain.tf.annular", "satchain.tf.pupil", "satchain.tf.zernike"),
}


def test_split_modules_keep_every_public_name_at_the_old_path():
    import importlib

    for module, names in OLD_NAMES.items():
        m = importlib.import_module(module)
        missing = [n for n in names.split() if not hasattr(m, n)]
        assert not missing, f"{module} lost {missing}"
        assert set(names.split()) <= set(m.__all__) | {"as_run_config", "run"}, module


def test_split_modules_re_export_every_public_name_of_their_parts():
    import importlib

    for module, parts in PARTS.items():
        m = importlib.import_module(module)
        for part in parts:
            p = importlib.import_module(part if "." in part else f"{module}.{part}")
            for name in p.__all__:
                assert getattr(m, name) is getattr(p, name), f"{module}.{name} is not {p.__name__}.{name}"
                assert name in m.__all__, f"{name} of {p.__name__} is missing from {module}.__all__"
