"""The inverse question over two keys: a feasibility map by the budget.

``feasibility_map(system, [(key1, lo1, hi1), (key2, lo2, hi2)], targets)`` computes every target's margin on an
``n x n`` grid of the two keys (:func:`satchain.studies.design.design_figures` per cell); a cell is feasible where every
margin is >= 0. :mod:`satchain.report.design_map` writes it as CSV and draws it (each target's margin = 0 line over the
feasible cells).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from satchain.config.system import ImagingSystem
from satchain.errors import ConfigError
from satchain.studies.design import Target, _current, design_figures, fixed_and_following, vary_system

__all__ = ["FeasibilityMap", "feasibility_map"]


@dataclass
class FeasibilityMap:
    """Each target's value and margin on a grid: arrays indexed ``[i2, i1]`` (key2 along rows, key1 along
    columns)."""

    keys: tuple[str, str]
    x1: np.ndarray
    x2: np.ndarray
    targets: list[Target]
    held_fixed: list[str]
    values: dict[str, np.ndarray]
    margins: dict[str, np.ndarray]

    @property
    def feasible(self) -> np.ndarray:
        return np.all([m >= 0 for m in self.margins.values()], axis=0)

    def rows(self) -> list[dict[str, Any]]:
        """One row per grid cell: the two keys' values, each target quantity's value and margin, feasible."""
        out = []
        feas = self.feasible
        for i2, v2 in enumerate(self.x2):
            for i1, v1 in enumerate(self.x1):
                row: dict[str, Any] = {self.keys[0]: float(v1), self.keys[1]: float(v2)}
                row.update({q: float(a[i2, i1]) for q, a in self.values.items()})
                row.update({f"margin {t}": float(self.margins[str(t)][i2, i1]) for t in self.targets})
                row["feasible"] = bool(feas[i2, i1])
                out.append(row)
        return out

    def to_dict(self) -> dict[str, Any]:
        feas = self.feasible
        ranges = {}
        for k, x, axis in ((self.keys[0], self.x1, 0), (self.keys[1], self.x2, 1)):
            ok = x[np.any(feas, axis=axis)]
            ranges[k] = [float(ok.min()), float(ok.max())] if ok.size else None
        return {
            "keys": list(self.keys),
            "grid": {self.keys[0]: self.x1.tolist(), self.keys[1]: self.x2.tolist()},
            "held_fixed": self.held_fixed,
            "targets": [str(t) for t in self.targets],
            "feasible_cells": int(feas.sum()),
            "cells": int(feas.size),
            "feasible_ranges_on_the_grid": ranges,
            "best": self.best(),
        }

    def best(self) -> dict[str, dict[str, float]]:
        """Each target's best margin on the grid, its value and where."""
        out = {}
        for t in self.targets:
            m = self.margins[str(t)]
            i2, i1 = np.unravel_index(int(np.argmax(m)), m.shape)
            out[str(t)] = {
                self.keys[0]: float(self.x1[i1]),
                self.keys[1]: float(self.x2[i2]),
                "value": float(self.values[t.quantity][i2, i1]),
                "margin": float(m[i2, i1]),
            }
        return out

    def unreachable(self) -> list[str]:
        """One line per target met nowhere on the grid (its best value and where), or one line when each is met
        somewhere but never all together."""
        lines = []
        for t in self.targets:
            b = self.best()[str(t)]
            if b["margin"] < 0:
                where = ", ".join(f"{k} = {b[k]:.6g}" for k in self.keys)
                lines.append(
                    f"target {t} is not met on the grid: the best {t.quantity} found is {b['value']:.6g} at {where}"
                )
        if not lines and not self.feasible.any():
            lines.append(
                f"targets {', '.join(map(str, self.targets))} are each met somewhere on the grid but never together"
            )
        return lines


def _axis(system: ImagingSystem, key: str, lo: float, hi: float, n: int) -> np.ndarray:
    """``n`` values from ``lo`` to ``hi``; an integer key's distinct nearest integers."""
    x = np.linspace(lo, hi, n)
    current = _current(system, key)
    if isinstance(current, int) and not isinstance(current, bool):
        x = np.unique(np.round(x))
    return x


def feasibility_map(
    system: ImagingSystem, vary: list[tuple[str, float, float]], targets: list[Target], *, n: int = 21
) -> FeasibilityMap:
    """Every target's margin on an ``n x n`` grid of two keys (the corners validated first).

    Examples
    --------
    >>> from satchain.config.system import load_preset
    >>> from satchain.studies.design import parse_target
    >>> m = feasibility_map(load_preset("ankarasat3"), [("optics.aperture_diameter_m", 0.5, 1.0),
    ...     ("detector.tdi_stages", 8, 32)], [parse_target("snr>=60")], n=3)
    >>> m.feasible.shape
    (3, 3)
    """
    if len(vary) != 2:
        raise ConfigError(f"--vary given {len(vary)} times: a feasibility map takes two keys")
    (k1, lo1, hi1), (k2, lo2, hi2) = vary
    if k1 == k2:
        raise ConfigError(f"--vary {k1!r} given twice: give two different keys")
    if not targets:
        raise ConfigError("--target: give at least one target, e.g. 'niirs>=5.2'")
    for a in (lo1, hi1):
        for b in (lo2, hi2):
            vary_system(vary_system(system, k1, a), k2, b)
    x1, x2 = _axis(system, k1, lo1, hi1, n), _axis(system, k2, lo2, hi2, n)
    quantities = list(dict.fromkeys(t.quantity for t in targets))
    values = {q: np.empty((x2.size, x1.size)) for q in quantities}
    for i2, v2 in enumerate(x2):
        for i1, v1 in enumerate(x1):
            f = design_figures(vary_system(vary_system(system, k1, float(v1)), k2, float(v2)))
            for q in quantities:
                values[q][i2, i1] = f[q]
    margins = {str(t): (1.0 if t.op in (">=", ">") else -1.0) * (values[t.quantity] - t.threshold) for t in targets}
    held = [f"varying {k}: {fixed_and_following(system, k)[0]}" for k in (k1, k2)]
    return FeasibilityMap((k1, k2), x1, x2, list(targets), held, values, margins)
