"""Registry of vessel models: built-in data files, user files and plugins.

Three ways a model becomes available to :func:`get_model`:

1. **Packaged data files.** Every ``ship_models/data/<name>.toml`` is registered as
   ``<name>`` (the 4-DOF model :class:`~ship_models.umeda_4dof.Umeda4DOF` of that
   vessel) and ``<name>_surge`` (its uncoupled surge model
   :class:`~ship_models.surge.SurgeModel`), e.g. ``"purse_seiner"`` and
   ``"purse_seiner_surge"``.
2. **Code.** :func:`register_model` as a decorator or a call::

       @register_model("my_ferry", description="twin-screw ferry")
       def my_ferry(**options):
           return Umeda4DOF("path/to/ferry.toml", **options)

3. **Plugins.** Another installed package declares an entry point in the group
   ``broachkit.models`` (see :data:`ENTRY_POINT_GROUP`)::

       [project.entry-points."broachkit.models"]
       my_ferry = "my_pkg.ferry:make_model"      # a factory: make_model(**options)
       my_tug = "my_pkg.tug:VESSEL"              # a VesselData, or a path to a .toml

   Entry points are discovered lazily, once, on first use of the registry, and each
   is imported only when its model is requested. A plugin that fails to import
   raises :class:`PluginError` naming the entry point; the other models keep
   working. A plugin whose name is already taken (by a built-in model or an
   earlier plugin) is ignored with a logged warning.

A path to a user's own vessel file works wherever a name does:
``get_model("path/to/my_vessel.toml")`` or :func:`load_model_file`.
"""

from __future__ import annotations

import dataclasses
import inspect
import logging
import os
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from importlib.metadata import EntryPoint, entry_points
from pathlib import Path
from typing import Any, Literal

from .estimation import VesselModelData, resolve_vessel
from .surge import SurgeModel
from .umeda_4dof import Umeda4DOF
from .vessel import Coefficient, VesselData, available_vessels, load_vessel

log = logging.getLogger(__name__)

#: Entry-point group through which other packages add vessel models.
ENTRY_POINT_GROUP = "broachkit.models"

#: Model kinds: the 4-DOF model of a vessel file, its surge reduction, or any other
#: dynamical system (a custom factory).
KINDS = ("4dof", "surge", "custom")

_NAME_RE = re.compile(r"^[A-Za-z][A-Za-z0-9_.\-]*$")
_MODEL_CLASSES: dict[str, type] = {"4dof": Umeda4DOF, "surge": SurgeModel}

VesselRef = str | Path | VesselData
Overrides = Mapping[str, float | Coefficient]


class PluginError(RuntimeError):
    """A ``broachkit.models`` entry point could not be loaded or gave an unusable object.

    The message names the entry point (``name = module:attr``) and its distribution.
    """


@dataclass(frozen=True)
class ModelEntry:
    """One registered model.

    Attributes
    ----------
    name : str
        Registry name (what :func:`get_model` takes).
    kind : str
        ``"4dof"``, ``"surge"``, ``"custom"``, or ``"plugin"`` for an entry point not
        loaded yet.
    origin : str
        ``"built-in"``, ``"registered"`` (by :func:`register_model`) or
        ``"entry point"``.
    description : str
        One line for listings.
    factory : callable or None
        ``factory(**options) -> System``; None for a plugin not loaded yet.
    vessel : str, Path, VesselData or None
        The vessel behind a ``4dof``/``surge`` model (packaged name, file or data).
    options : tuple of str or None
        Keyword options the factory accepts (None: not checked).
    entry_point : EntryPoint or None
        For plugins.
    """

    name: str
    kind: str
    origin: str
    description: str = ""
    factory: Callable[..., Any] | None = field(default=None, repr=False)
    vessel: VesselRef | None = field(default=None, repr=False)
    options: tuple[str, ...] | None = None
    entry_point: EntryPoint | None = field(default=None, repr=False)

    @property
    def target(self) -> str:
        """Where the model comes from: vessel file, entry point value or factory name."""
        if self.entry_point is not None:
            dist = _dist_name(self.entry_point)
            return f"{self.entry_point.value}" + (f" ({dist})" if dist else "")
        if isinstance(self.vessel, VesselData):
            return self.vessel.path or f"VesselData {self.vessel.name!r}"
        if self.vessel is not None:
            return str(_vessel_path(self.vessel))
        f = self.factory
        return f"{getattr(f, '__module__', '?')}:{getattr(f, '__qualname__', repr(f))}"

    def as_dict(self) -> dict[str, Any]:
        """Plain dictionary for JSON listings."""
        return {
            "name": self.name,
            "kind": self.kind,
            "origin": self.origin,
            "description": self.description,
            "target": self.target,
            "options": list(self.options) if self.options is not None else None,
        }


_REGISTRY: dict[str, ModelEntry] = {}
_plugins_discovered = False


# ---------------------------------------------------------------------- helpers
def _dist_name(ep: EntryPoint) -> str:
    dist = getattr(ep, "dist", None)
    if dist is None:
        return ""
    try:
        return f"{dist.metadata['Name']} {dist.version}"
    except Exception:  # pragma: no cover - broken metadata
        return ""


def _vessel_path(ref: str | Path) -> Path:
    p = Path(ref)
    if not p.suffix and not p.exists():
        from .vessel import DATA_DIR

        return DATA_DIR / f"{p.name}.toml"
    return p


def _check_name(name: Any) -> str:
    if not isinstance(name, str) or not _NAME_RE.match(name):
        raise ValueError(
            f"`name` must be a string of letters, digits, '_', '.', '-' starting with a "
            f"letter, got {name!r}"
        )
    if name.endswith(".toml"):
        raise ValueError(f"`name` must not end in '.toml' (that denotes a file), got {name!r}")
    return name


def _accepted_options(fn: Callable[..., Any], skip: tuple[str, ...] = ()) -> tuple[str, ...] | None:
    """Keyword options a callable accepts; None if it takes ``**kwargs`` or is opaque."""
    try:
        sig = inspect.signature(fn)
    except (TypeError, ValueError):
        return None
    names = []
    for p in sig.parameters.values():
        if p.kind == p.VAR_KEYWORD:
            return None
        if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY) and p.name not in skip:
            names.append(p.name)
    return tuple(names)


def _check_options(name: str, accepted: tuple[str, ...] | None, options: Mapping[str, Any]) -> None:
    if accepted is None:
        return
    unknown = sorted(set(options) - set(accepted))
    if unknown:
        raise ValueError(
            f"unknown option(s) {unknown} for model {name!r}; accepted options are "
            f"{sorted(accepted)}"
        )


def _load_vessel(ref: VesselRef, overrides: Overrides | None) -> VesselData:
    vessel = ref if isinstance(ref, VesselData) else load_vessel(ref)
    if overrides:
        if not isinstance(overrides, Mapping):
            raise ValueError(
                f"`overrides` must be a mapping {{dotted_key: value}}, got {overrides!r}"
            )
        vessel = vessel.with_overrides(overrides)
    return vessel


def _vessel_factory(ref: VesselRef, kind: str) -> tuple[Callable[..., Any], tuple[str, ...]]:
    cls = _MODEL_CLASSES[kind]

    def factory(*, overrides: Overrides | None = None, **options: Any) -> Any:
        return cls(_load_vessel(ref, overrides), **options)

    accepted = _accepted_options(cls.__init__, skip=("self", "vessel")) or ()
    factory.__doc__ = (
        f"{cls.__name__} of vessel {ref if not isinstance(ref, VesselData) else ref.name!r}"
    )
    return factory, ("overrides", *accepted)


def _is_system(obj: Any) -> bool:
    return all(hasattr(obj, a) for a in ("state_names", "param_names", "f", "jacobian"))


def vessel_model(
    data: VesselModelData | VesselData, kind: Literal["4dof", "surge"] = "4dof", **options: Any
) -> Any:
    """The model of kind ``kind`` (4-DOF by default) of resolved vessel data.

    Parameters
    ----------
    data : VesselModelData or VesselData
        Resolved data (used as they are) or a vessel (resolved with the options'
        ``waves`` builder, default Froude-Krylov strips).
    kind : {"4dof", "surge"}
    **options
        Keyword options of the model class.
    """
    if kind not in _MODEL_CLASSES:
        raise ValueError(f"`kind` must be '4dof' or 'surge', got {kind!r}")
    return _MODEL_CLASSES[kind](data, **options)


# ---------------------------------------------------------------------- registration
def register_model(
    name: str,
    factory: Callable[..., Any] | None = None,
    *,
    description: str = "",
    replace: bool = False,
) -> Any:
    """Register a model factory under ``name`` (call or decorator).

    Parameters
    ----------
    name : str
        Registry name: letters, digits, ``_ . -``, starting with a letter.
    factory : callable, optional
        ``factory(**options) -> System`` (a class or a function). Omit it to use
        ``register_model`` as a decorator.
    description : str
        One line shown by ``broachkit vessels list``.
    replace : bool
        Allow replacing an existing registration (default: refuse).

    Returns
    -------
    callable
        ``factory`` (so the decorator leaves the decorated object unchanged), or the
        decorator when ``factory`` is omitted.

    Raises
    ------
    ValueError
        Bad name, non-callable factory, or a name already registered.
    """
    _check_name(name)

    def deco(fn: Callable[..., Any]) -> Callable[..., Any]:
        if not callable(fn):
            raise ValueError(f"`factory` must be callable, got {type(fn).__name__}")
        _discover_plugins()
        old = _REGISTRY.get(name)
        if old is not None and not replace:
            raise ValueError(
                f"model name {name!r} is already registered ({old.origin}: {old.target}); "
                "pass replace=True to replace it"
            )
        doc = description or (inspect.getdoc(fn) or "").split("\n", 1)[0]
        _REGISTRY[name] = ModelEntry(
            name,
            "custom",
            "registered",
            doc,
            factory=fn,
            options=_accepted_options(fn),
        )
        return fn

    if factory is None:
        return deco
    return deco(factory)


def unregister_model(name: str) -> None:
    """Remove a registration (ValueError if ``name`` is not registered)."""
    _discover_plugins()
    if name not in _REGISTRY:
        raise ValueError(f"model {name!r} is not registered; registered: {list_models()}")
    del _REGISTRY[name]


def _register_vessel(name: str, ref: VesselRef, kind: str, origin: str, description: str) -> None:
    factory, opts = _vessel_factory(ref, kind)
    _REGISTRY[name] = ModelEntry(name, kind, origin, description, factory, ref, opts)


def _register_packaged() -> None:
    for stem in available_vessels():
        if not _NAME_RE.match(stem):
            log.warning("packaged vessel file %r ignored: not a valid model name", stem)
            continue
        _register_vessel(stem, stem, "4dof", "built-in", "")
        _register_vessel(f"{stem}_surge", stem, "surge", "built-in", "")


# ---------------------------------------------------------------------- plugins
def _discover_plugins() -> None:
    """Register (without importing) every ``broachkit.models`` entry point, once."""
    global _plugins_discovered
    if _plugins_discovered:
        return
    _plugins_discovered = True
    try:
        eps = list(entry_points(group=ENTRY_POINT_GROUP))
    except Exception as exc:  # pragma: no cover - broken environment metadata
        log.warning("could not read %s entry points: %s", ENTRY_POINT_GROUP, exc)
        return
    for ep in eps:
        if not _NAME_RE.match(ep.name) or ep.name.endswith(".toml"):
            log.warning("entry point %r = %r ignored: not a valid model name", ep.name, ep.value)
            continue
        old = _REGISTRY.get(ep.name)
        if old is not None:
            log.warning(
                "entry point %s = %s (%s) ignored: model name %r is already registered (%s: %s)",
                ep.name,
                ep.value,
                _dist_name(ep) or "unknown distribution",
                ep.name,
                old.origin,
                old.target,
            )
            continue
        _REGISTRY[ep.name] = ModelEntry(
            ep.name, "plugin", "entry point", f"plugin {ep.value}", entry_point=ep
        )


def refresh_plugins() -> None:
    """Forget discovered plugins and discover again (after installing a package)."""
    global _plugins_discovered
    for name in [n for n, e in _REGISTRY.items() if e.origin == "entry point"]:
        del _REGISTRY[name]
    _plugins_discovered = False
    _discover_plugins()


def _plugin_error(ep: EntryPoint, what: str) -> PluginError:
    dist = _dist_name(ep)
    return PluginError(
        f"vessel plugin entry point `{ep.name} = {ep.value}` (group {ENTRY_POINT_GROUP!r}"
        f"{', distribution ' + dist if dist else ''}) {what}"
    )


def _load_plugin(entry: ModelEntry) -> ModelEntry:
    ep = entry.entry_point
    if ep is None:  # pragma: no cover - plugins always have one
        raise RuntimeError(f"model {entry.name!r} has neither a factory nor an entry point")
    try:
        obj = ep.load()
    except Exception as exc:
        raise _plugin_error(ep, f"failed to load: {type(exc).__name__}: {exc}") from exc
    if isinstance(obj, VesselData) or isinstance(obj, (str, os.PathLike)):
        ref: VesselRef = obj if isinstance(obj, VesselData) else Path(obj)
        if isinstance(ref, Path) and not ref.is_file():
            raise _plugin_error(ep, f"points to {str(ref)!r}, which is not a vessel file")
        factory, opts = _vessel_factory(ref, "4dof")
        name = ref.name if isinstance(ref, VesselData) else ref.stem
        loaded = dataclasses.replace(
            entry,
            kind="4dof",
            factory=factory,
            vessel=ref,
            options=opts,
            description=f"4-DOF model of vessel {name!r} (plugin {ep.value})",
        )
    elif callable(obj):
        doc = (inspect.getdoc(obj) or "").split("\n", 1)[0]
        loaded = dataclasses.replace(
            entry,
            kind="custom",
            factory=obj,
            options=_accepted_options(obj),
            description=doc or entry.description,
        )
    else:
        raise _plugin_error(
            ep,
            f"gave a {type(obj).__name__}; expected a model factory (a class or function "
            "returning a System), a VesselData, or a path to a vessel .toml file",
        )
    _REGISTRY[entry.name] = loaded
    return loaded


# ---------------------------------------------------------------------- lookup
def _looks_like_path(name: Any) -> bool:
    if isinstance(name, os.PathLike):
        return True
    return isinstance(name, str) and (
        name.endswith(".toml") or "/" in name or (os.sep != "/" and os.sep in name)
    )


def list_models() -> list[str]:
    """Sorted names of all registered models (plugins included, not imported)."""
    _discover_plugins()
    return sorted(_REGISTRY)


def model_info(name: str) -> ModelEntry:
    """The registry entry of ``name`` (plugins are not imported).

    Raises
    ------
    ValueError
        Unknown name (the message lists the available names).
    """
    _discover_plugins()
    if not isinstance(name, str) or name not in _REGISTRY:
        raise ValueError(
            f"unknown model {name!r}; available models: {list_models()} "
            "(or give the path to a vessel .toml file)"
        )
    entry = _REGISTRY[name]
    if entry.origin == "built-in" and not entry.description and entry.vessel is not None:
        try:
            meta = load_vessel(entry.vessel).meta  # type: ignore[arg-type]
            what = "surge model" if entry.kind == "surge" else "4-DOF model"
            desc = f"{what}: {meta.get('description', entry.vessel)}"
        except ValueError as exc:
            desc = f"(invalid vessel file: {exc})"
        entry = dataclasses.replace(entry, description=desc)
        _REGISTRY[name] = entry
    return entry


def _loaded(name: str) -> tuple[ModelEntry, Callable[..., Any]]:
    entry = model_info(name)
    if entry.factory is None:
        entry = _load_plugin(entry)
    if entry.factory is None:  # pragma: no cover - _load_plugin always sets it
        raise RuntimeError(f"model {name!r} has no factory")
    return entry, entry.factory


def get_model(name: str | os.PathLike[str], **options: Any) -> Any:
    """Build a registered model, or the 4-DOF model of a vessel file.

    Parameters
    ----------
    name : str or path
        A registered name (see :func:`list_models`), or the path to a vessel
        ``.toml`` file (any string ending in ``.toml`` or containing ``/``).
    **options
        Passed to the model's factory. Vessel models accept ``overrides`` (a mapping
        ``{dotted_key: value or Coefficient}`` applied with
        :meth:`~ship_models.vessel.VesselData.with_overrides`) and the keyword
        options of :class:`~ship_models.umeda_4dof.Umeda4DOF` (``saturation``,
        ``saturation_order``, ``wave_lift``); surge models accept ``overrides``.

    Returns
    -------
    System
        A :class:`continuation.System` (for vessel models) or whatever dynamical
        system a registered factory returns.

    Raises
    ------
    ValueError
        Unknown name (message lists the available names), unknown option, or a bad
        vessel file (:class:`~ship_models.vessel.VesselFileError` names the field).
    PluginError
        The model's plugin fails to import or returns something that is not a
        dynamical system.

    Examples
    --------
    >>> from ship_models import get_model
    >>> m = get_model("purse_seiner", saturation=False)
    >>> m2 = get_model("purse_seiner", overrides={"loading.GM": 1.1})
    """
    if _looks_like_path(name):
        return load_model_file(name, **options)
    entry, factory = _loaded(str(name))
    _check_options(entry.name, entry.options, options)
    try:
        model = factory(**options)
    except Exception as exc:
        if entry.entry_point is not None and not isinstance(exc, ValueError):
            raise _plugin_error(
                entry.entry_point, f"failed to build the model: {type(exc).__name__}: {exc}"
            ) from exc
        raise
    if not _is_system(model):
        msg = f"returned a {type(model).__name__}, not a dynamical system"
        if entry.entry_point is not None:
            raise _plugin_error(entry.entry_point, msg)
        raise ValueError(f"the factory of model {entry.name!r} {msg}")
    return model


def load_model_file(
    path: str | os.PathLike[str],
    *,
    kind: Literal["4dof", "surge"] = "4dof",
    overrides: Overrides | None = None,
    **options: Any,
) -> Any:
    """Read a vessel ``.toml`` file and build its model.

    Parameters
    ----------
    path : str or path
        The vessel file (format of :mod:`ship_models.vessel`).
    kind : {"4dof", "surge"}
        :class:`~ship_models.umeda_4dof.Umeda4DOF` (default) or
        :class:`~ship_models.surge.SurgeModel`.
    overrides : mapping, optional
        Coefficients to replace (e.g. measured values), see
        :meth:`~ship_models.vessel.VesselData.with_overrides`.
    **options
        Keyword options of the model class.

    Raises
    ------
    ValueError
        Missing file, bad ``kind`` or option; :class:`~ship_models.vessel.VesselFileError`
        (a ValueError) naming the field of a bad file.
    """
    if kind not in ("4dof", "surge"):
        raise ValueError(f"`kind` must be '4dof' or 'surge', got {kind!r}")
    p = Path(path)
    if not p.is_file():
        raise ValueError(f"`path`: no vessel file {str(p)!r}")
    factory, opts = _vessel_factory(p, kind)
    _check_options(str(p), opts, {"overrides": overrides, **options})
    return factory(overrides=overrides, **options)


def get_vessel_data(
    name: str | os.PathLike[str], *, overrides: Overrides | None = None
) -> VesselModelData:
    """The resolved vessel (file values plus estimates) behind a model or file.

    Resolves the vessel without building the CasADi model when the registry knows
    its vessel (packaged files, user files, plugins that give a vessel); for a custom
    factory the model is built and its ``data`` attribute returned.

    Parameters
    ----------
    name : str or path
        Registered name or path to a vessel ``.toml`` file.
    overrides : mapping, optional
        Coefficients to replace before resolving.

    Returns
    -------
    VesselModelData

    Raises
    ------
    ValueError
        Unknown name, bad file, or a model that has no vessel data.
    PluginError
        A plugin that fails to load.
    """
    if _looks_like_path(name):
        p = Path(name)
        if not p.is_file():
            raise ValueError(f"`name`: no vessel file {str(p)!r}")
        return resolve_vessel(_load_vessel(p, overrides))
    entry, _ = _loaded(str(name))
    if entry.vessel is not None:
        return resolve_vessel(_load_vessel(entry.vessel, overrides))
    model = get_model(entry.name, **({"overrides": overrides} if overrides else {}))
    data = getattr(model, "data", None)
    if not isinstance(data, VesselModelData):
        raise ValueError(f"model {entry.name!r} has no vessel data (it is a custom system)")
    return data


_register_packaged()

__all__ = [
    "ENTRY_POINT_GROUP",
    "KINDS",
    "ModelEntry",
    "PluginError",
    "get_model",
    "get_vessel_data",
    "list_models",
    "load_model_file",
    "model_info",
    "refresh_plugins",
    "register_model",
    "unregister_model",
    "vessel_model",
]
