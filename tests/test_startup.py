"""Issue 21, point 3: ``import satchain`` and ``satchain --help`` load only what they need (lazy imports): the
public names resolve on first use, and the help screens never import numpy, pydantic or the engine. Times are
printed by ``benchmarks/bench_startup.py``, not asserted here."""

import json
import subprocess
import sys

HEAVY = ("numpy", "scipy", "pydantic", "matplotlib", "satchain.config.system", "satchain.engine")


def _loaded(code: str, heavy=HEAVY) -> list[str]:
    probe = code + "\nimport sys, json\nprint(json.dumps(sorted(sys.modules)))"
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout
    mods = json.loads(out.strip().splitlines()[-1])
    return [m for m in mods if any(m == h or m.startswith(h + ".") for h in heavy)]


def test_import_satchain_loads_no_heavy_module():
    assert _loaded("import satchain") == []


def test_the_help_screens_load_no_heavy_module():
    for argv in (["--help"], ["measure", "--help"]):
        code = (
            "import sys\nfrom satchain.cli.main import app\nsys.argv = ['satchain', *" + repr(argv) + "]\n"
            "try:\n    app()\nexcept SystemExit:\n    pass"
        )
        # typer itself imports pydantic for a sub-command group's help (typer._adapters): not ours to avoid
        assert _loaded(code, tuple(h for h in HEAVY if h != "pydantic")) == [], argv


def test_the_lazy_names_resolve_to_the_real_objects():
    import satchain
    from satchain.config.system import ImagingSystem, load_preset

    assert satchain.ImagingSystem is ImagingSystem and satchain.load_preset is load_preset
    assert set(satchain.__all__) <= set(dir(satchain))
    assert len(satchain.__all__) == len(set(satchain.__all__))


def test_the_run_path_never_imports_scipy_stats_or_signal():
    """scipy.signal and scipy.stats cost about a second to import, so the run's hot paths (the low-mean
    Poisson quantile, the calibration's tail sum, the slanted edge's spectrum on and off the FFT grid)
    use scipy.special and scipy.fft instead."""
    code = (
        "import numpy as np\n"
        "from satchain.engine.sensor import _poisson_ppf\n"
        "from satchain.measure.auto._calibrate import _convolve_valid\n"
        "from satchain.measure.edge._numerics import _dft_rows\n"
        "from satchain.measure.edge import measure_edge\n"
        "u = np.random.default_rng(0).random((8, 8))\n"
        "_poisson_ppf(u, np.full(u.shape, 5.0))\n"
        "_convolve_valid(np.ones((20, 20)), np.ones((3, 3)))\n"
        "_dft_rows(np.ones((2, 50)), 0.0123, 30)\n"
        "x = np.arange(60)[None, :] - 30 - 0.1 * np.arange(60)[:, None]\n"
        "measure_edge(0.2 + 0.6 / (1 + np.exp(-x / 0.6)))\n"
    )
    assert _loaded(code, ("scipy.stats", "scipy.signal")) == []


def test_the_figure_helper_preloads_no_fft_nor_measurement_code():
    """The run folder's figure helper starts while the run simulates (on the same two cores): what it preloads
    (``pipeline._FIGURE_MODULES``) must not pull scipy.fft (0.2 s, the pupil's FFTs import it when used) nor
    the measurement code (the result keys live in ``satchain.measure._keys``)."""
    from satchain.pipeline import _FIGURE_MODULES

    code = "import importlib\n" + "".join(f"importlib.import_module({m!r})\n" for m in _FIGURE_MODULES)
    heavy = ("scipy.fft", "satchain.measure.edge", "satchain.measure.edge._crossings", "satchain.engine")
    assert _loaded(code, heavy) == []
