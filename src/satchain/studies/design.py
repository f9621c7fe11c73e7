"""The inverse question by the budget: which values of one system key meet every target.

``design(system, key, lo, hi, targets)`` varies one system key over ``[lo, hi]`` (the other keys held fixed, but
for the one that follows it: varying the aperture holds the focal length, so the f-number follows), computes the
budget's figures per value (:func:`design_figures`), and finds where each target's margin changes sign: a coarse
scan brackets each sign change and :func:`scipy.optimize.brentq` finds the root to ``xtol``. The answer is the
union of the intervals where every margin is >= 0, with each target's value and margin at both ends of each
interval; an end inside the range is a root of its binding target's margin (~0 there).

A target is ``<quantity> (>=|<=|>|<) <number>``, the quantity one of :data:`QUANTITIES`.
"""

from __future__ import annotations

import functools
import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from satchain.config.system import ImagingSystem
from satchain.errors import ConfigError

__all__ = [
    "QUANTITIES",
    "DesignResult",
    "Target",
    "design",
    "design_figures",
    "fixed_and_following",
    "parse_target",
    "parse_vary",
    "vary_system",
]

#: The budget quantities a target may name, with what each is.
QUANTITIES: dict[str, str] = {
    "niirs": "GIQE 5 NIIRS (prediction.quality, at nadir)",
    "rer": "relative edge response, geometric mean of ACT and ALT",
    "rer_act": "relative edge response, across-track",
    "rer_alt": "relative edge response, along-track",
    "snr": "the contrast SNR the GIQE uses (prediction.quality)",
    "mtf_nyquist_act": "system MTF at the detector Nyquist, across-track",
    "mtf_nyquist_alt": "system MTF at the detector Nyquist, along-track",
    "gsd_m": "ground sample distance (m)",
    "q": "Q = lambda_eff N / pitch",
}

_OPS: dict[str, Callable[[float, float], float]] = {
    ">=": lambda v, t: v - t,
    ">": lambda v, t: v - t,
    "<=": lambda v, t: t - v,
    "<": lambda v, t: t - v,
}
_TARGET_RE = re.compile(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\s*(>=|<=|>|<)\s*(\S+)\s*$")


@dataclass(frozen=True)
class Target:
    """One target: ``quantity op threshold``; its margin is > 0 where it is met (in the quantity's unit)."""

    quantity: str
    op: str
    threshold: float

    def margin(self, figures: dict[str, float]) -> float:
        return _OPS[self.op](figures[self.quantity], self.threshold)

    def __str__(self) -> str:
        return f"{self.quantity}{self.op}{self.threshold:g}"


def parse_target(text: str) -> Target:
    """Parse ``"niirs>=5.2"``; a target that cannot be parsed or names an unknown quantity raises ConfigError.

    Examples
    --------
    >>> parse_target("snr >= 60")
    Target(quantity='snr', op='>=', threshold=60.0)
    """
    m = _TARGET_RE.match(text)
    if m is None:
        raise ConfigError(f"--target {text!r}: must be '<quantity> (>=|<=|>|<) <number>', e.g. 'niirs>=5.2'")
    name, op, num = m.groups()
    if name not in QUANTITIES:
        raise ConfigError(f"--target {text!r}: unknown quantity {name!r}: must be one of {', '.join(QUANTITIES)}")
    try:
        value = float(num)
    except ValueError:
        raise ConfigError(f"--target {text!r}: {num!r} is not a number") from None
    if not math.isfinite(value):
        raise ConfigError(f"--target {text!r}: the threshold must be finite")
    return Target(name, op, value)


def parse_vary(text: str) -> tuple[str, float, float]:
    """Parse ``"optics.aperture_diameter_m=0.2:1.5"`` into ``(key, lo, hi)`` with ``lo < hi``.

    Examples
    --------
    >>> parse_vary("optics.aperture_diameter_m=0.2:1.5")
    ('optics.aperture_diameter_m', 0.2, 1.5)
    """
    key, eq, rng = text.partition("=")
    lo_s, colon, hi_s = rng.partition(":")
    if not eq or not colon or not key.strip():
        raise ConfigError(
            f"--vary {text!r}: must be '<section>.<key>=<lo>:<hi>', e.g. optics.aperture_diameter_m=0.2:1.5"
        )
    try:
        lo, hi = float(lo_s), float(hi_s)
    except ValueError:
        raise ConfigError(f"--vary {text!r}: {lo_s!r} and {hi_s!r} must be numbers") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise ConfigError(f"--vary {text!r}: the range must be finite with lo < hi")
    return key.strip(), lo, hi


def fixed_and_following(system: ImagingSystem, key: str) -> tuple[str, str | None]:
    """What a variation of ``key`` holds fixed and which key follows it (a sentence, and the follower or None)."""
    o = system.optics
    if key == "optics.aperture_diameter_m":
        f = system.derived()["focal_length_m"]
        return f"optics.focal_length_m = {f:.6g} m and every other key held fixed", "optics.f_number"
    if key == "optics.focal_length_m":
        return f"optics.aperture_diameter_m = {o.aperture_diameter_m:.6g} m and every other key held fixed", (
            "optics.f_number"
        )
    if key == "optics.f_number":
        return f"optics.aperture_diameter_m = {o.aperture_diameter_m:.6g} m and every other key held fixed", (
            "optics.focal_length_m"
        )
    return "every other key held fixed", None


def vary_system(system: ImagingSystem, key: str, value: float) -> ImagingSystem:
    """``system`` with the dotted ``key`` set to ``value``, validated (a bad key or value raises ConfigError naming
    it). Varying the aperture holds the focal length fixed (the f-number follows); an integer key (e.g.
    ``detector.tdi_stages``) takes the nearest integer."""
    if key == "optics.aperture_diameter_m":
        d = system.to_dict()
        d["optics"]["focal_length_m"] = system.derived()["focal_length_m"]
        d["optics"].pop("f_number", None)
        d["optics"]["aperture_diameter_m"] = float(value)
        return ImagingSystem.from_dict(d)
    current = _current(system, key)
    v: float | int = int(round(value)) if isinstance(current, int) and not isinstance(current, bool) else float(value)
    return system.replace({key: v})


def _current(system: ImagingSystem, key: str) -> Any:
    """The value of a dotted key in ``system`` (None where it is not a plain entry)."""
    node: Any = system.to_dict()
    for part in key.split("."):
        if not isinstance(node, dict) or part not in node:
            return None
        node = node[part]
    return node


def _budget_results(system: ImagingSystem) -> dict[str, Any]:
    from satchain.prediction.budget import budget_results

    out: dict[str, Any] = budget_results(system)
    return out


def design_figures(system: ImagingSystem) -> dict[str, float]:
    """The budget quantities a design target may name (:data:`QUANTITIES`) for ``system``.

    Examples
    --------
    >>> from satchain.config.system import load_preset
    >>> round(design_figures(load_preset("ankarasat3"))["gsd_m"], 2)
    0.49
    """
    res = _budget_results(system)
    q = res.get("quality")
    if q is None:
        from satchain.prediction.quality import predict_quality

        q = predict_quality(system).to_dict()
    der, ny = res["derived"], res["mtf_at_nyquist"]
    return {
        "niirs": float(q["giqe5"]),
        "rer": float(q["rer"]),
        "rer_act": float(q["rer_act"]),
        "rer_alt": float(q["rer_alt"]),
        "snr": float(q["snr"]),
        "mtf_nyquist_act": float(ny["act"]),
        "mtf_nyquist_alt": float(ny["alt"]),
        "gsd_m": float(der["gsd_m"]),
        "q": float(der["q_effective"]),
    }


@dataclass
class DesignResult:
    """The feasible intervals of ``key`` in ``[lo, hi]`` and each target's value and margin at their ends."""

    key: str
    lo: float
    hi: float
    targets: list[Target]
    held_fixed: str
    follows: str | None
    intervals: list[dict[str, Any]] = field(default_factory=list)
    best: dict[str, dict[str, float]] = field(default_factory=dict)
    evaluations: int = 0

    @property
    def feasible(self) -> bool:
        return bool(self.intervals)

    def unreachable(self) -> list[str]:
        """One line per target never met over the range (its best value and where), or, when each target is met
        somewhere but never all together, one line saying so."""
        lines = []
        for t in self.targets:
            b = self.best[str(t)]
            if b["margin"] < 0:
                lines.append(
                    f"target {t} is not met for {self.key} in [{self.lo:g}, {self.hi:g}]: the best {t.quantity} "
                    f"found is {b['value']:.6g} at {self.key} = {b['at']:.6g}"
                )
        if not lines and not self.intervals:
            names = ", ".join(map(str, self.targets))
            lines.append(f"targets {names} are each met somewhere in [{self.lo:g}, {self.hi:g}] but never together")
        return lines

    def to_dict(self) -> dict[str, Any]:
        return {
            "key": self.key,
            "range": [self.lo, self.hi],
            "held_fixed": self.held_fixed,
            "follows": self.follows,
            "targets": [str(t) for t in self.targets],
            "feasible": self.feasible,
            "intervals": self.intervals,
            "best": self.best,
            "unreachable": self.unreachable(),
            "budget_evaluations": self.evaluations,
            "method": "coarse scan to bracket each target's margin sign change, then scipy.optimize.brentq",
        }


def _margin_at(t: Target, cache: dict[float, dict[str, float]], x: float) -> float:
    return t.margin(cache[x])


def _root(
    brentq: Callable[..., Any], t: Target, figures: Callable[[float], dict[str, float]], a: float, b: float, xtol: float
) -> float:
    """The root of ``t``'s margin in ``[a, b]`` (a sign change) by Brent's method."""

    def margin(x: float) -> float:
        return t.margin(figures(float(x)))

    return float(brentq(margin, a, b, xtol=xtol))


def _roots(
    targets: list[Target],
    figures: Callable[[float], dict[str, float]],
    xs: list[float],
    xtol: float,
    brentq: Callable[..., Any],
) -> list[tuple[float, str]]:
    """Every sign change of every target's margin over the scan ``xs``, refined by Brent's method."""
    roots: list[tuple[float, str]] = []
    for t in targets:
        m = [t.margin(figures(x)) for x in xs]
        for i in range(len(xs) - 1):
            if m[i] == 0.0 and i > 0:
                roots.append((xs[i], str(t)))
            elif m[i] * m[i + 1] < 0:
                roots.append((_root(brentq, t, figures, xs[i], xs[i + 1], xtol), str(t)))
    return roots


def _spans(
    targets: list[Target], figures: Callable[[float], dict[str, float]], edges: list[float]
) -> list[list[float]]:
    """The maximal runs of the pieces between consecutive ``edges`` whose midpoint meets every target."""
    spans: list[list[float]] = []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        f = figures(0.5 * (a + b))
        if all(t.margin(f) >= 0 for t in targets):
            if spans and spans[-1][1] == a:
                spans[-1][1] = b
            else:
                spans.append([a, b])
    return spans


def design(
    system: ImagingSystem,
    key: str,
    lo: float,
    hi: float,
    targets: list[Target],
    *,
    n_scan: int = 33,
    xtol: float | None = None,
) -> DesignResult:
    """The range of ``key`` in ``[lo, hi]`` that meets every target, by root finding on the budget.

    Both ends of the range are validated first (a key the system lacks, or a range outside the key's allowed
    range, raises ConfigError naming it). ``xtol`` defaults to ``1e-9 * (hi - lo)``.

    Examples
    --------
    >>> from satchain.config.system import load_preset
    >>> r = design(load_preset("ankarasat3"), "optics.aperture_diameter_m", 0.3, 1.0, [parse_target("niirs>=5.2")])
    >>> [round(i["lo"], 3) for i in r.intervals]
    [0.698]
    """
    from scipy.optimize import brentq

    if not targets:
        raise ConfigError("--target: give at least one target, e.g. 'niirs>=5.2'")
    for end in (lo, hi):
        vary_system(system, key, end)
    held, follows = fixed_and_following(system, key)
    xtol = 1e-9 * (hi - lo) if xtol is None else xtol
    cache: dict[float, dict[str, float]] = {}

    def figures(x: float) -> dict[str, float]:
        if x not in cache:
            cache[x] = design_figures(vary_system(system, key, x))
        return cache[x]

    xs = [float(x) for x in np.linspace(lo, hi, n_scan)]
    roots = _roots(targets, figures, xs, xtol, brentq)
    binding = {r: name for r, name in roots}
    result = DesignResult(key, lo, hi, list(targets), held, follows)
    for a, b in _spans(targets, figures, sorted({lo, hi, *binding})):
        fa, fb = figures(a), figures(b)
        result.intervals.append(
            {
                "lo": a,
                "hi": b,
                "lo_binding": binding.get(a) if a != lo else None,
                "hi_binding": binding.get(b) if b != hi else None,
                "values_lo": {t.quantity: fa[t.quantity] for t in targets},
                "values_hi": {t.quantity: fb[t.quantity] for t in targets},
                "margins_lo": {str(t): t.margin(fa) for t in targets},
                "margins_hi": {str(t): t.margin(fb) for t in targets},
            }
        )
    for t in targets:
        x_best = max(cache, key=functools.partial(_margin_at, t, cache))
        result.best[str(t)] = {"at": x_best, "value": cache[x_best][t.quantity], "margin": t.margin(cache[x_best])}
    result.evaluations = len(cache)
    return result
