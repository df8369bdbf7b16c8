"""Vessel data files: every number with its unit, source and status.

A vessel is described by one TOML file (read with :mod:`tomllib`) in which every
number is a table::

    GM = { value = 1.0, unit = "m", source = "Umeda (1999) Table 1", status = "given" }

``status`` is one of ``given`` (from the reference paper's table), ``measured``
(from a cited test report), ``estimated`` (a named method computed it),
``assumed`` (a stated engineering assumption) or ``calibrated`` (solved so that the
model reproduces a stated target, e.g. a published critical Froude number; the
source names the target and where it came from). Free-text metadata (strings) are
allowed only in the ``[vessel]`` section; there ``wave_surge_model`` selects the
wave surge-force model (one of :data:`WAVE_SURGE_MODELS`, default
``"froude_krylov"``).

Uncertainties (optional) live in an ``[uncertainties]`` section keyed by the dotted
name of any schema coefficient, given in the file or filled by the estimation
pipeline::

    [uncertainties]
    "hydrodynamics.m_x" = { value = 0.3, type = "relative", source = "..." }
    "rudder.x_H_over_L" = { value = 0.05, type = "absolute", unit = "-", source = "..." }

``value`` is a *standard* uncertainty (one standard deviation, as in the ISO Guide
to the Expression of Uncertainty in Measurement), relative to the coefficient's
value or absolute in ``unit``; ``source`` states where it comes from (a method's
published accuracy, or an assumption stated as one). See :class:`Uncertainty`.

:func:`load_vessel` parses and validates a file and returns an immutable
:class:`VesselData`. Validation refuses, with a :class:`VesselFileError` naming the
field by its dotted path (e.g. ``loading.GM``): a missing required field; a table
without ``value``/``unit``/``source``/``status`` or with extra keys; an unknown
status, unit, section or key (no silent typos); a non-finite value; non-positive
lengths, breadth, drafts, mass or periods, or beyond any ship's (``L_pp`` > 500 m,
``L_pp/B`` outside [1.5, 20], ``B/d_m`` outside [0.5, 15]); ``GM <= 0`` or so large
that G lies below the keel (``KG = KM - GM < 0``); a wave steeper than the
breaking limit ``H/lambda = 1/7`` (Michell, J.H. 1893, "The highest waves in water",
Phil. Mag. 36:430-437).

Nothing is silently defaulted: coefficients that the file does not give are
filled by the estimation pipeline (:func:`ship_models.estimation.resolve_vessel`),
which records them with status ``estimated`` and the method in ``source``.
"""

from __future__ import annotations

import tomllib
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .validation import check_file_size, check_plausible
from .vessel_checks import check_table, check_uncertainty, validate
from .vessel_curves import CurveData, CurveError, parse_curves
from .vessel_schema import (
    _UNITS,
    BREAKING_STEEPNESS,
    HEEL_METHODS,
    HULL_TYPES,
    METHOD_CHOICES,
    PROPELLER_METHODS,
    RESISTANCE_METHODS,
    SCHEMA,
    STATUSES,
    UNCERTAINTY_TYPES,
    WAVE_SURGE_MODELS,
    Coefficient,
    Field,
    Uncertainty,
    VesselFileError,
    _si_factor,
)
from .vessel_toml import dump_vessel, vessel_to_toml

DATA_DIR = Path(__file__).resolve().parent / "data"


class _MethodChoice:
    """A method choice of :class:`VesselData` (read-only attribute of the same name):
    ``[vessel] <name>``, or the first of :data:`METHOD_CHOICES` ``[name]`` when the
    file names none."""

    def __init__(self, doc: str) -> None:
        self.__doc__ = doc

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name
        self.__doc__ = f"{self.__doc__[:-1]} (``[vessel] {name}``)."

    def __get__(self, obj: Any, objtype: type | None = None) -> Any:
        if obj is None:
            return self
        return str(obj.meta.get(self.name, METHOD_CHOICES[self.name][0]))


@dataclass(frozen=True)
class VesselData(Mapping[str, Coefficient]):
    """An immutable, validated vessel description.

    It is a read-only mapping from dotted keys (``"loading.GM"``) to
    :class:`Coefficient`.

    Attributes
    ----------
    name : str
        Short identifier (``[vessel] name``).
    meta : mapping of str to str
        Free-text metadata of the ``[vessel]`` section.
    coefficients : mapping of str to Coefficient
        All numbers, by dotted key.
    path : str
        File it was read from ("" when built in code).
    uncertainties : mapping of str to Uncertainty
        Standard uncertainties by dotted key (section ``[uncertainties]``); a key may
        name a coefficient that only the estimation pipeline fills.
    """

    name: str
    meta: Mapping[str, str]
    coefficients: Mapping[str, Coefficient] = field(repr=False)
    path: str = ""
    uncertainties: Mapping[str, Uncertainty] = field(default_factory=dict, repr=False)
    curves: Mapping[str, CurveData] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        coeffs = dict(self.coefficients)
        validate(coeffs)
        check_plausible(coeffs)  # relations between fields (plausibility)
        meta = dict(self.meta)
        for key, allowed in (*METHOD_CHOICES.items(), ("hull_type", HULL_TYPES)):
            if key in meta and meta[key] not in allowed:
                raise VesselFileError(f"`vessel.{key}` must be one of {allowed}, got {meta[key]!r}")
        curves = dict(self.curves)
        if meta.get("resistance_method") == "table" and "resistance" not in curves:
            raise VesselFileError(
                "`vessel.resistance_method` = 'table' needs a `curves.resistance` table"
            )
        if meta.get("propeller_method") == "curve" and "K_T" not in curves:
            raise VesselFileError("`vessel.propeller_method` = 'curve' needs a `curves.K_T` entry")
        object.__setattr__(self, "curves", curves)
        unc = dict(self.uncertainties)
        for k, u in unc.items():
            if not isinstance(u, Uncertainty):
                unc[k] = check_uncertainty(k, u)
            else:
                check_uncertainty(k, u.as_dict() | {"unit": u.unit})
        object.__setattr__(self, "coefficients", coeffs)
        object.__setattr__(self, "meta", meta)
        object.__setattr__(self, "uncertainties", unc)

    resistance_method = _MethodChoice("The selected resistance method.")
    propeller_method = _MethodChoice("The selected open-water propeller model.")
    heel_derivatives_method = _MethodChoice("The selected heel-derivative estimate.")
    wave_surge_model = _MethodChoice("The selected wave surge-force model.")

    def sigma(self, key: str) -> float | None:
        """Standard uncertainty of ``key`` in the coefficient's unit (None if none given)."""
        k = self._resolve_key(key)
        u = self.uncertainties.get(k)
        return None if u is None else u.sigma(k, self.coefficients[k])

    # Mapping protocol
    def __getitem__(self, key: str) -> Coefficient:
        return self.coefficient(key)

    def __iter__(self) -> Iterator[str]:
        return iter(self.coefficients)

    def __len__(self) -> int:
        return len(self.coefficients)

    def __hash__(self) -> int:
        return hash(
            (
                self.name,
                tuple(sorted(self.coefficients.items())),
                tuple(sorted(self.meta.items())),
                tuple(sorted(self.curves.items())),
            )
        )

    def _resolve_key(self, key: str) -> str:
        if key in self.coefficients:
            return key
        if "." not in key:
            hits = [k for k in self.coefficients if k.split(".", 1)[1] == key]
            if len(hits) == 1:
                return hits[0]
            if len(hits) > 1:
                raise KeyError(f"key {key!r} is ambiguous: {hits}; use the dotted path")
        raise KeyError(f"no coefficient {key!r} in vessel {self.name!r}")

    def coefficient(self, key: str) -> Coefficient:
        """The :class:`Coefficient` at dotted ``key`` (or a unique bare name)."""
        return self.coefficients[self._resolve_key(key)]

    def get(self, key: str, default: Any = None) -> Any:  # type: ignore[override]
        """Value of ``key`` in SI units (``default`` if absent, else KeyError if no default)."""
        try:
            k = self._resolve_key(key)
        except KeyError:
            if default is not None:
                return default
            raise
        c = self.coefficients[k]
        return c.value * _si_factor(k, c.unit)

    def has(self, key: str) -> bool:
        """True if the coefficient is present."""
        try:
            self._resolve_key(key)
        except KeyError:
            return False
        return True

    def to_dict(self) -> dict[str, Any]:
        """Nested plain dictionary (JSON-serialisable), sections as in the file."""
        out: dict[str, Any] = {"vessel": {"name": self.name, **self.meta}}
        for k, c in self.coefficients.items():
            sec, name = k.split(".", 1)
            out.setdefault(sec, {})[name] = c.as_dict()
        if self.uncertainties:
            out["uncertainties"] = {k: u.as_dict() for k, u in self.uncertainties.items()}
        if self.curves:
            out["curves"] = {k: c.as_dict() for k, c in self.curves.items()}
        return out

    def with_overrides(self, overrides: Mapping[str, float | Coefficient]) -> VesselData:
        """A copy with some coefficients replaced (validated again).

        Parameters
        ----------
        overrides : mapping
            ``{dotted_key: Coefficient}``, or ``{dotted_key: float}``: a bare number
            keeps the unit of the existing entry (SI unit of the schema if absent) and
            is recorded with ``source="user override"`` and ``status="measured"``.

        Raises
        ------
        VesselFileError
            For unknown keys or values that fail validation.
        """
        coeffs = dict(self.coefficients)
        for key, val in overrides.items():
            sec, _, name = key.partition(".")
            if sec not in SCHEMA or name not in SCHEMA[sec]:
                raise VesselFileError(f"`{key}`: unknown coefficient; use a dotted schema key")
            if isinstance(val, Coefficient):
                coeffs[key] = val
            else:
                default_unit = next(iter(_UNITS[SCHEMA[sec][name].dim]))
                unit = coeffs[key].unit if key in coeffs else default_unit
                coeffs[key] = Coefficient(float(val), unit, "user override", "measured")
        return VesselData(self.name, self.meta, coeffs, self.path, self.uncertainties, self.curves)

    def with_estimates(self, estimates: Mapping[str, Coefficient]) -> VesselData:
        """A copy with estimated coefficients added (existing keys are kept)."""
        coeffs = dict(self.coefficients)
        for key, c in estimates.items():
            coeffs.setdefault(key, c)
        return VesselData(self.name, self.meta, coeffs, self.path, self.uncertainties, self.curves)

    def summary(self) -> list[tuple[str, float, str, str, str]]:
        """Rows ``(key, value, unit, status, source)`` sorted by key."""
        return [
            (k, c.value, c.unit, c.status, c.source) for k, c in sorted(self.coefficients.items())
        ]


def parse_vessel(doc: Mapping[str, Any], path: str = "") -> VesselData:
    """Build a :class:`VesselData` from a parsed TOML document (nested dictionaries).

    Raises
    ------
    VesselFileError
        Naming the offending field.
    """
    meta_raw = doc.get("vessel", {})
    if not isinstance(meta_raw, Mapping):
        raise VesselFileError("`vessel` must be a table of strings")
    meta: dict[str, str] = {}
    for k, v in meta_raw.items():
        if not isinstance(v, str):
            raise VesselFileError(f"`vessel.{k}` must be a string (numbers go in other sections)")
        meta[k] = v
    name = meta.pop("name", "") or (Path(path).stem if path else "vessel")
    coeffs: dict[str, Coefficient] = {}
    unc_raw = doc.get("uncertainties", {})
    if not isinstance(unc_raw, Mapping):
        raise VesselFileError("`uncertainties` must be a table keyed by dotted coefficient names")
    uncertainties = {str(k): check_uncertainty(str(k), u) for k, u in unc_raw.items()}
    try:
        curves = parse_curves(doc.get("curves", {}))
    except CurveError as exc:
        raise VesselFileError(str(exc)) from None
    for sec, body in doc.items():
        if sec in ("vessel", "uncertainties", "curves"):
            continue
        if sec not in SCHEMA:
            raise VesselFileError(
                f"`{sec}`: unknown section; sections are "
                f"{['vessel', *SCHEMA, 'curves', 'uncertainties']}"
            )
        if not isinstance(body, Mapping):
            raise VesselFileError(f"`{sec}` must be a table")
        for key, raw in body.items():
            dotted = f"{sec}.{key}"
            if key not in SCHEMA[sec]:
                raise VesselFileError(
                    f"`{dotted}`: unknown key {key!r} in [{sec}]; allowed are {list(SCHEMA[sec])}"
                )
            coeffs[dotted] = check_table(dotted, raw)
    return VesselData(name, meta, coeffs, path, uncertainties, curves)


def available_vessels() -> list[str]:
    """Names of the vessel files packaged in ``ship_models/data``."""
    return sorted(p.stem for p in DATA_DIR.glob("*.toml"))


def load_vessel(path_or_name: str | Path) -> VesselData:
    """Read and validate a vessel file.

    Parameters
    ----------
    path_or_name : str or Path
        A path to a ``.toml`` file, or the name of a packaged vessel
        (see :func:`available_vessels`), e.g. ``"purse_seiner"``.

    Returns
    -------
    VesselData

    Raises
    ------
    ValueError
        If the file does not exist (message lists the packaged vessels).
    VesselFileError
        If the file is malformed or non-physical (message names the field).
    """
    p = Path(path_or_name)
    if not p.suffix and not p.exists():
        p = DATA_DIR / f"{p.name}.toml"
    if not p.is_file():
        raise ValueError(
            f"no vessel file {str(path_or_name)!r}; packaged vessels are {available_vessels()}"
        )
    check_file_size(p)
    try:
        with p.open("rb") as fh:
            doc = tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise VesselFileError(f"{p}: not valid TOML: {exc}") from exc
    return parse_vessel(doc, str(p))


__all__ = [
    "BREAKING_STEEPNESS",
    "Coefficient",
    "HEEL_METHODS",
    "HULL_TYPES",
    "PROPELLER_METHODS",
    "RESISTANCE_METHODS",
    "UNCERTAINTY_TYPES",
    "Uncertainty",
    "WAVE_SURGE_MODELS",
    "dump_vessel",
    "vessel_to_toml",
    "Field",
    "SCHEMA",
    "STATUSES",
    "VesselData",
    "VesselFileError",
    "available_vessels",
    "load_vessel",
    "parse_vessel",
    "validate",
]
