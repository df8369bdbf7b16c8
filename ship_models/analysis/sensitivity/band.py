"""Linear propagation of the vessel file's uncertainties to the critical Fn, optionally sampled."""

from __future__ import annotations

import dataclasses
import logging
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from continuation.casadi_compile import uncompiled
from continuation.typing import FloatArray

from ...estimation import build_vessel_model
from ...vessel import SCHEMA, VesselData, load_vessel
from .adjoint import resolve_at
from .factors import SYSTEM_PARAMS
from .rebuild import model_at
from .result import Sensitivity, SensitivityEntry

log = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class UncertaintyBand:
    """Standard uncertainty of the critical Fn from the vessel file's uncertainties.

    Attributes
    ----------
    Fn : float
        Critical Fn at the nominal coefficients.
    sigma_linear : float
        ``sqrt(sum_i (dFn*/dtheta_i sigma_i)^2)`` (independent coefficients).
    contributions : tuple of (str, float)
        ``(key, |dFn*/dtheta| sigma)`` sorted by decreasing size.
    samples : ndarray, shape (S,)
        Re-solved critical Fn of the sampled coefficient sets (empty if not sampled).
    sample_linear : ndarray, shape (S,)
        The linear prediction ``Fn + sum_i dFn/dtheta_i (theta_i - theta_i0)`` for each.
    failed : int
        Samples whose connection did not converge (not in ``samples``).
    coverage : float
        Multiple of sigma for the reported band (1.96: about 95 % for a normal law).
    """

    Fn: float
    sigma_linear: float
    contributions: tuple[tuple[str, float], ...]
    samples: FloatArray = field(default_factory=lambda: np.zeros(0))
    sample_linear: FloatArray = field(default_factory=lambda: np.zeros(0))
    failed: int = 0
    coverage: float = 1.96

    @property
    def band(self) -> tuple[float, float]:
        """``Fn -+ coverage sigma_linear``."""
        return (self.Fn - self.coverage * self.sigma_linear,
                self.Fn + self.coverage * self.sigma_linear)  # fmt: skip

    @property
    def sigma_sampled(self) -> float:
        """Sample standard deviation of the re-solved Fn (nan without samples)."""
        return float(np.std(self.samples, ddof=1)) if self.samples.size > 1 else math.nan

    def contains(self, value: float) -> bool:
        """Whether ``value`` lies inside :attr:`band`."""
        lo, hi = self.band
        return lo <= value <= hi

    def to_json(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {
            "Fn": self.Fn,
            "sigma_linear": self.sigma_linear,
            "coverage": self.coverage,
            "band": list(self.band),
            "contributions": [{"key": k, "sigma_Fn": v} for k, v in self.contributions],
            "n_samples": int(self.samples.size),
            "failed_samples": self.failed,
            "sigma_sampled": None if self.samples.size < 2 else self.sigma_sampled,
            "samples": self.samples.tolist(),
            "sample_linear": self.sample_linear.tolist(),
        }


def uncertainty_band(
    sens: Sensitivity,
    vessel: VesselData | str | Path = "purse_seiner",
    *,
    n_samples: int = 0,
    seed: int = 0,
    scale: float = 1.0,
    coverage: float = 1.96,
) -> UncertaintyBand:
    r"""Linear propagation of the file's standard uncertainties, optionally sampled.

    ``sigma_Fn^2 = sum_i (dFn*/dtheta_i sigma_i)^2`` over the coefficients that carry
    an uncertainty (assumed independent). With ``n_samples > 0``, that many coefficient
    sets are drawn (independent normal laws with standard deviations ``scale sigma_i``,
    redrawn where a value would leave the schema's range) and the connection is
    re-solved for each from the nominal one (full ``critical_fn_bvp``): the sampled
    spread confirms (or not) the linear one; ``scale < 1`` probes the linear regime.

    Parameters
    ----------
    sens : Sensitivity
        From :func:`critical_fn_sensitivity` for this vessel (must include the keys
        that carry uncertainties).
    vessel : VesselData, str or Path
    n_samples : int
    seed : int
    scale : float
        Factor on every sigma for the samples (the linear band is for ``scale = 1``).
    coverage : float
        Band half-width in multiples of sigma.
    """
    raw = vessel if isinstance(vessel, VesselData) else load_vessel(vessel)
    resolved = build_vessel_model(raw).vessel
    by_key = {e.key: e for e in sens.entries}
    contrib = []
    used: list[SensitivityEntry] = []
    for k in resolved.uncertainties:
        if k not in resolved.coefficients:
            continue
        if k not in by_key:
            raise ValueError(f"`sens` has no entry for {k!r}, which carries an uncertainty")
        e = by_key[k]
        s = resolved.sigma(k) or 0.0
        contrib.append((k, abs(e.dFn_dtheta) * s))
        used.append(dataclasses.replace(e, sigma=s))
    contrib.sort(key=lambda kv: -kv[1])
    sigma = math.sqrt(sum(v * v for _, v in contrib))
    samples: list[float] = []
    linear: list[float] = []
    failed = 0
    if n_samples > 0:
        rng = np.random.default_rng(seed)
        m0 = sens.connection.orbit.problem.system  # rebuilt per sample (wave forces kept)
        sys_p = {}
        for _ in range(int(n_samples)):
            changes: dict[str, float] = {}
            dlin = 0.0
            for e in used:
                th = _draw(rng, e, scale)
                changes[e.key] = th
                dlin += e.dFn_dtheta * (th - e.value)
            sys_p = {SYSTEM_PARAMS[k]: changes.pop(k) for k in list(changes) if k in SYSTEM_PARAMS}
            try:
                m = model_at(raw, changes, resolved=resolved, model=m0)
                with uncompiled():  # a one-off model (see continuation.casadi_compile)
                    fn = resolve_at(sens.connection, m, same_discretisation=False, params=sys_p)
            except (ValueError, ArithmeticError) as exc:
                log.warning("sample failed: %s", exc)
                failed += 1
                continue
            samples.append(fn)
            linear.append(sens.Fn + dlin)
    return UncertaintyBand(sens.Fn, sigma, tuple(contrib), np.array(samples),
                           np.array(linear), failed, coverage)  # fmt: skip


def _draw(rng: np.random.Generator, e: SensitivityEntry, scale: float) -> float:
    sec, name = e.key.split(".", 1)
    spec = SCHEMA[sec][name]
    from ...vessel import _si_factor  # noqa: PLC0415

    f = _si_factor(e.key, e.unit)
    for _ in range(100):
        th = e.value + scale * (e.sigma or 0.0) * rng.standard_normal()
        v = th * f
        low_ok = v > spec.low if spec.low_open else v >= spec.low
        if low_ok and v <= spec.high:
            return float(th)
    return float(e.value)


def dominant(band: UncertaintyBand, n: int = 3) -> list[str]:
    """Keys of the ``n`` largest contributions to the band's width."""
    return [k for k, _ in band.contributions[:n]]
