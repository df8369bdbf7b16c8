"""What a step of the main job was computed from, so a finished step is reused only for it.

A step of ``broachkit reproduce`` is reused from an earlier run only when the record of
its inputs written beside its results (:data:`INPUTS_FILE`) equals the inputs of this
run, as the sweep layer keys its tasks (:mod:`continuation.sweep.keys`):

- ``vessel``: sha256 of the content of the vessel file the studies use (``None`` for
  the engine demo, which uses no vessel);
- ``settings``: the options that change what a step computes (the study scripts'
  source: packaged or a ``--studies`` folder);
- ``code``: digests of the source that computes the step: the engine
  (``continuation``) and, for a study, ``ship_models`` and the study's script with
  every script of its folder it imports (found by reading its ``import`` statements),
  for the demo its command module.

:func:`compare` says, in words, why a record is valid or which input differs.
"""

from __future__ import annotations

import ast
import hashlib
import json
from collections.abc import Iterable, Mapping
from functools import lru_cache
from pathlib import Path
from typing import Any

#: File in a step folder recording the inputs its results were computed from.
INPUTS_FILE = "inputs.json"

#: The vessel of the packaged studies (``ship_models.purse_seiner()``).
STUDY_VESSEL = "purse_seiner"


def file_sha256(path: Path) -> str:
    """sha256 of a file's content."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


@lru_cache(maxsize=32)
def _package_digest(root: str) -> str:
    h = hashlib.sha256()
    base = Path(root)
    for f in sorted(base.rglob("*.py")):
        h.update(str(f.relative_to(base)).encode())
        h.update(f.read_bytes())
    return h.hexdigest()[:16]


def package_digest(name: str) -> str:
    """Digest of every ``.py`` file of the importable package ``name``."""
    import importlib.util

    spec = importlib.util.find_spec(name)
    if spec is None or spec.origin is None:
        return "missing"
    return _package_digest(str(Path(spec.origin).parent))


def _imported_names(path: Path, package: str) -> set[str]:
    """Module names of ``path``'s folder that it imports (``studies.x``, ``.x``, ``x``)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            mods = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            mod = node.module or ""
            if node.level:  # relative: ``from ._common import x`` / ``from . import x``
                mods = [mod] if mod else [a.name for a in node.names]
            elif mod == package:
                mods = [a.name for a in node.names]
            else:
                mods = [mod]
        else:
            continue
        for m in mods:
            parts = m.split(".")
            if parts[0] == package and len(parts) > 1:
                parts = parts[1:]
            names.add(parts[0])
    return names


def script_digest(path: Path, package: str = "studies") -> str:
    """Digest of a script and of every script of its folder it imports, transitively.

    ``package`` is the name under which the folder's scripts import each other
    (``from studies._common import ...``).
    """
    path = Path(path)
    folder = path.parent
    seen: dict[str, Path] = {}
    todo = [path]
    while todo:
        f = todo.pop()
        if f.name in seen:
            continue
        seen[f.name] = f
        for name in _imported_names(f, package):
            dep = folder / f"{name}.py"
            if dep.is_file() and dep.name not in seen:
                todo.append(dep)
    h = hashlib.sha256()
    for name in sorted(seen):
        h.update(name.encode())
        h.update(seen[name].read_bytes())
    return h.hexdigest()[:16]


def vessel_file(name: str = STUDY_VESSEL) -> Path | None:
    """The vessel file behind a registered name (``None`` when it has no file)."""
    from ship_models import get_vessel_data

    path = getattr(get_vessel_data(name).vessel, "path", None)
    return Path(path) if path else None


def step_inputs(
    step: str, script: Path | None, *, vessel: Path | None, settings: Mapping[str, Any]
) -> dict[str, Any]:
    """The inputs of one step: ``{"vessel", "settings", "code"}`` (JSON-able).

    Parameters
    ----------
    step : str
        The step's key (``demo``, ``fig02_05``, ...).
    script : Path or None
        The study script (``None`` for the engine demo).
    vessel : Path or None
        The vessel file the studies use.
    settings : mapping
        Options that change what the step computes.
    """
    code = {"continuation": package_digest("continuation")}
    if script is None:
        from .commands import demo

        code["demo"] = script_digest(Path(demo.__file__), "broachkit_cli")
        return {"vessel": None, "settings": dict(settings), "code": code}
    code["ship_models"] = package_digest("ship_models")
    code["study"] = script_digest(script)
    digest = file_sha256(vessel) if vessel is not None else None
    return {
        "vessel": None if vessel is None else {"file": str(vessel), "sha256": digest},
        "settings": dict(settings),
        "code": code,
    }


def read_record(folder: Path) -> dict[str, Any] | None:
    """The inputs recorded in a step folder (``None`` if absent or unreadable)."""
    try:
        rec = json.loads((Path(folder) / INPUTS_FILE).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return rec if isinstance(rec, dict) else None


def _differs(old: Mapping[str, Any], new: Mapping[str, Any]) -> Iterable[str]:
    ov, nv = old.get("vessel"), new.get("vessel")
    if (ov or {}).get("sha256") != (nv or {}).get("sha256"):
        yield "the vessel file changed" if ov and nv else "the vessel input changed"
    if old.get("settings") != new.get("settings"):
        keys = sorted(
            k
            for k in set(old.get("settings", {})) | set(new.get("settings", {}))
            if old.get("settings", {}).get(k) != new.get("settings", {}).get(k)
        )
        yield f"settings changed ({', '.join(keys)})"
    oc, nc = old.get("code", {}), new.get("code", {})
    parts = sorted(k for k in set(oc) | set(nc) if oc.get(k) != nc.get(k))
    if parts:
        yield f"code changed ({', '.join(parts)})"


def compare(record: Mapping[str, Any] | None, inputs: Mapping[str, Any]) -> tuple[bool, str]:
    """Whether a recorded step may be reused for ``inputs``, and why (one phrase).

    Returns
    -------
    (bool, str)
        ``(True, "same vessel file (sha256 1a2b3c4d), settings and code")`` or
        ``(False, "the vessel file changed")`` etc.
    """
    if record is None:
        return False, "no record of the inputs it was computed from"
    why = list(_differs(record, inputs))
    if why:
        return False, "; ".join(why)
    v = inputs.get("vessel")
    head = f"same vessel file (sha256 {v['sha256'][:8]}), " if v else "no vessel, same "
    return True, head + "settings and code"


__all__ = [
    "INPUTS_FILE",
    "STUDY_VESSEL",
    "compare",
    "file_sha256",
    "package_digest",
    "read_record",
    "script_digest",
    "step_inputs",
    "vessel_file",
]
