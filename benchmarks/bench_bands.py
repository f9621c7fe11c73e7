"""What a banded simulation costs: every band of ``ankarasat3-pms`` (PAN + blue, green, red, NIR at 4x the pitch)
vs its PAN band alone, on the paper scene.

Both runs are :func:`satchain.simulate_bands` on ``satchain run``'s default ground truth (the paper layout,
:func:`satchain.scene.layout.paper_layout`, a grey scene) at ``--pixel`` m (default 0.07), noise on, reflectance
units: ``bands=["pan"]`` (the reference, measured in the same run) and all five bands. Printed: the wall time of
each (best of ``--repeat``, default 2), their ratio (issue 32's target: <= 2.5), the same for their CPU time (all
threads; steadier where other work shares the CPUs), and, for the all-band run, where
each band's time goes -- the system OTF's evaluations (the engine's transfer and the node check of
:func:`satchain.engine.bands_shared.band_otf`), the scene's rendering, and the rest of forming it (decimation, frame,
spectrum, fold, noise) -- with the number of optics wavelengths each band's OTF used (and the system's own). The
first MS band's "form" holds its grid's shared stage 1 and frame transform (:mod:`satchain.engine.bands_shared`);
the others' only their own OTF, fold and noise.

``--background-material NAME`` makes the scene spectral (its background a library material, e.g. dry_grass): each
band then sees its own grey scene, so each renders its own ground and decimates it (nothing shared but the plan).

Run:  PYTHONPATH=src python benchmarks/bench_bands.py [--repeat N] [--pixel M] [--background-material NAME]
"""

from __future__ import annotations

import argparse
import time
from collections import defaultdict

import satchain.engine.bands as eb
from satchain import load_preset
from satchain.engine.bands_shared import band_otf
from satchain.scene.layout import Scene, paper_layout
from satchain.tf.budget import SystemOTF

SPENT: dict[str, float] = defaultdict(float)


def _timed(key: str, fn):
    def wrapper(*args, **kwargs):
        t0 = time.perf_counter()
        try:
            return fn(*args, **kwargs)
        finally:
            SPENT[key] += time.perf_counter() - t0

    return wrapper


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--pixel", type=float, default=0.07, help="ground-truth pixel (m); satchain run's default scene")
    ap.add_argument("--background-material", default=None, help="a library material: the scene made spectral")
    a = ap.parse_args()
    if a.repeat < 1:
        ap.error(f"--repeat = {a.repeat}: must be a whole number >= 1")
    system, scene = load_preset("ankarasat3-pms"), paper_layout()
    if a.background_material:
        from satchain.scene.materials import material
        from satchain.scene.spectral import MaterialSlot

        slot = MaterialSlot(None, "background", material(a.background_material))
        scene = Scene(scene.width_m, scene.height_m, scene.items, scene.background, materials=(slot,))
    run = lambda bands: eb.simulate_bands(scene, system, pixel_m=a.pixel, bands=bands, noise=True, seed=3)  # noqa: E731
    run(["pan"])  # imports and first-call costs out of the figures
    pan, every, pan_cpu, every_cpu = [], [], [], []
    for _ in range(a.repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        run(["pan"])
        pan.append(time.perf_counter() - t0)
        pan_cpu.append(time.process_time() - c0)
        t0, c0 = time.perf_counter(), time.process_time()
        run(None)
        every.append(time.perf_counter() - t0)
        every_cpu.append(time.process_time() - c0)
    ratio = min(every) / min(pan)
    rows, cols = scene.shape_px(a.pixel)
    kind = f"background {a.background_material}" if a.background_material else "grey"
    print(f"paper scene ({kind}) {cols} x {rows} px at {a.pixel} m; ankarasat3-pms; noise on; best of {a.repeat}")
    print(f"PAN only:             {min(pan):6.2f} s")
    print(f"all 5 bands:          {min(every):6.2f} s")
    print(f"ratio (all / PAN):    {ratio:6.2f}   (target <= 2.5: {'met' if ratio <= 2.5 else 'NOT met'})")
    print(
        f"CPU time (all threads): PAN {min(pan_cpu):.2f} s, all {min(every_cpu):.2f} s, ratio "
        f"{min(every_cpu) / min(pan_cpu):.2f} (steadier than wall time on a shared machine)"
    )
    _breakdown(run, system)


def _breakdown(run, system) -> None:
    """One more all-band run with the OTF, the rendering and each band's forming timed."""
    per_band: list[dict[str, float | int | str]] = []
    form, otf_call, render = eb._form_band, SystemOTF.__call__, Scene.render

    def form_band(layout, sys_, i, *args, **kwargs):
        before = dict(SPENT)
        t0 = time.perf_counter()
        out = form(layout, sys_, i, *args, **kwargs)
        total = time.perf_counter() - t0
        otf, ren = SPENT["otf"] - before.get("otf", 0.0), SPENT["render"] - before.get("render", 0.0)
        nodes = len(band_otf(out.system, sys_.bands[i]).system.optics.wavelengths_m) if sys_.bands else 1
        per_band.append({"band": out.name, "total": total, "otf": otf, "render": ren, "form": total - otf - ren,
                         "nodes": nodes, "own": len(out.system.optics.wavelengths_m)})  # fmt: skip
        return out

    eb._form_band = form_band  # type: ignore[assignment]
    SystemOTF.__call__ = _timed("otf", otf_call)  # type: ignore[method-assign]
    Scene.render = _timed("render", render)  # type: ignore[method-assign]
    try:
        run(None)
    finally:
        eb._form_band, SystemOTF.__call__, Scene.render = form, otf_call, render  # type: ignore[method-assign]
    print("per band (s):  band    total    OTF  render   form   OTF nodes (system's)")
    for r in per_band:
        print(f"              {r['band']:<6} {r['total']:6.2f} {r['otf']:6.2f} {r['render']:6.2f} {r['form']:6.2f}"
              f"   {r['nodes']:>3} ({r['own']})")  # fmt: skip


if __name__ == "__main__":
    main()
