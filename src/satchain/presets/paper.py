"""The reference paper's Table 1 and the fit that infers the parameters the paper omits.

The paper (AnkaraSat-3; ``shared/reference/paper.txt``) gives altitude, aperture, F# and pixel pitch,
but not the wavelength of its diffraction MTF, the central obscuration or the smear length. They are
inferred here by fitting Table 1's "Overall System MTF" column, ALT, with
:func:`satchain.tf.fitting.fit_mtf`, taking the column "Spatial Freq. (f_y) at Focal Plane [L/mm]" as
**cycles/mm** -- the only reading consistent with its MTF values (see :func:`read_table1`).

Run ``python -m satchain.presets.paper`` to repeat the fit; the values are recorded in
``ankarasat3.toml``.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from satchain.config.system import ImagingSystem, load_preset
from satchain.errors import SatchainIOError

__all__ = ["FITTED_PARAMETERS", "Table1", "fit_table1", "read_table1"]

FITTED_PARAMETERS = ("optics.wavelength_m", "optics.obscuration_ratio", "motion.smear_px")


@dataclass(frozen=True)
class Table1:
    """Table 1 of the paper, columns as printed, with satchain's reading of their units.

    ``period_m``: the bar period (one line pair) on the ground; ``ground_cy_per_m = 1 / period_m``;
    ``focal_column``: the printed focal-plane column ("L/mm"). It equals ``2 * ground_cy_per_m *
    range / focal_length`` -- i.e. *lines*/mm for the printed ground period -- yet the MTF column was
    evaluated at it as if it were cycles/mm (the detector sinc's zero, 170 cy/mm, and the paper's own
    MTF at Nyquist, 12.28 % at 85.0 cy/mm, both require that). So each MTF/CTF value belongs to the
    focal frequency ``focal_column`` cy/mm, whose ground period is half the printed one.
    """

    period_m: np.ndarray
    ground_cy_per_m: np.ndarray
    focal_column: np.ndarray
    system_mtf: np.ndarray
    ctf: np.ndarray

    @property
    def f_cy_per_mm(self) -> np.ndarray:
        """The frequencies at which the MTF and CTF columns were actually evaluated (cy/mm)."""
        return self.focal_column


def read_table1(path: str | Path | None = None) -> Table1:
    """Read Table 1 (the copy shipped with satchain by default, or ``path``).

    Examples
    --------
    >>> t = read_table1()
    >>> float(t.f_cy_per_mm[6]), float(t.system_mtf[6])
    (83.3333, 0.129)
    """
    if path is None:
        text = (resources.files("satchain.presets") / "ankarasat3_table1.csv").read_text()
    else:
        try:
            text = Path(path).read_text()
        except OSError as exc:
            raise SatchainIOError(f"table path {str(path)!r}: cannot be read ({exc.strerror})") from None
    rows = list(csv.DictReader(io.StringIO("".join(ln for ln in text.splitlines(True) if not ln.startswith("#")))))
    col = {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}
    return Table1(
        period_m=col["period_lpw_m"],
        ground_cy_per_m=col["ground_freq_lp_per_m"],
        focal_column=col["focal_freq_l_per_mm"],
        system_mtf=col["system_mtf"],
        ctf=col["ctf"],
    )


def fit_table1(start: ImagingSystem | None = None, *, table: Table1 | None = None):
    """Fit effective wavelength, obscuration ratio and ALT smear to Table 1's MTF column.

    ``start`` defaults to the packaged ``ankarasat3`` preset moved away from its recorded values, so
    the fit is a real search, not a confirmation.
    """
    from satchain.tf.fitting import fit_mtf

    t = read_table1() if table is None else table
    if start is None:
        start = load_preset("ankarasat3").replace(
            {"optics.wavelength_m": 5.5e-7, "optics.obscuration_ratio": 0.1, "motion.smear_px": 0.5}
        )
    return fit_mtf(t.f_cy_per_mm, t.system_mtf, start, parameters=FITTED_PARAMETERS, direction="alt")


def main() -> None:  # pragma: no cover - a console helper
    r = fit_table1()
    for k in r.parameters:
        print(f"{k:28s} = {r.values[k]:.6g} +/- {r.stderr[k]:.2g}")
    print(f"max |residual| = {r.max_abs_residual:.2e}, rms = {r.rms_residual:.2e}")
    t = read_table1()
    for f, m, fit in zip(t.f_cy_per_mm, t.system_mtf, r.mtf_model, strict=True):
        print(f"{f:9.4f} cy/mm  table {m:.4f}  model {fit:.4f}  diff {fit - m:+.4f}")


if __name__ == "__main__":  # pragma: no cover
    main()
