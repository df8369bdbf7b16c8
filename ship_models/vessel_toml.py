"""Writing a vessel back as the text of a vessel file (:func:`vessel_to_toml`), which
:func:`ship_models.vessel.load_vessel` reads back to the same numbers."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

from .vessel_curves import curves_to_toml
from .vessel_schema import SCHEMA, Coefficient

if TYPE_CHECKING:
    from .vessel import VesselData


def _toml_str(s: str) -> str:
    return json.dumps(s, ensure_ascii=True)  # a JSON string is a valid TOML basic string


def _toml_num(x: float) -> str:
    return repr(float(x))  # shortest repr: reads back to the same float


def vessel_to_toml(vessel: VesselData, header: str = "") -> str:
    """The vessel as the text of a vessel file (:func:`~ship_models.vessel.load_vessel`
    reads it back).

    Parameters
    ----------
    vessel : VesselData
    header : str
        Comment lines put at the top (each prefixed with ``# ``).
    """
    lines = [f"# {h}" if h else "#" for h in header.splitlines()] if header else []
    lines += ["", "[vessel]", f"name = {_toml_str(vessel.name)}"]
    lines += [f"{k} = {_toml_str(v)}" for k, v in vessel.meta.items()]
    by_sec: dict[str, list[tuple[str, Coefficient]]] = {}
    for k, c in vessel.coefficients.items():
        sec, name = k.split(".", 1)
        by_sec.setdefault(sec, []).append((name, c))
    for sec in SCHEMA:
        if sec not in by_sec:
            continue
        lines += ["", f"[{sec}]"]
        for name, c in by_sec[sec]:
            lines.append(
                f"{name} = {{ value = {_toml_num(c.value)}, unit = {_toml_str(c.unit)}, "
                f"source = {_toml_str(c.source)}, status = {_toml_str(c.status)} }}"
            )
    lines += curves_to_toml(vessel.curves)
    if vessel.uncertainties:
        lines += ["", "[uncertainties]"]
        for k, u in vessel.uncertainties.items():
            unit = f", unit = {_toml_str(u.unit)}" if u.type == "absolute" else ""
            lines.append(
                f"{_toml_str(k)} = {{ value = {_toml_num(u.value)}, type = {_toml_str(u.type)}"
                f"{unit}, source = {_toml_str(u.source)} }}"
            )
    return "\n".join(lines) + "\n"


def dump_vessel(vessel: VesselData, path: str | Path, header: str = "") -> Path:
    """Write :func:`vessel_to_toml` to ``path`` atomically (UTF-8); return the path."""
    from continuation.atomic import write_text

    return write_text(path, vessel_to_toml(vessel, header))
