"""Lazy re-exports of a package's public names (PEP 562 module ``__getattr__``).

The engine's packages re-export the names of their sub-modules (``from continuation
import System``). Importing all those sub-modules eagerly costs a single query of the
command line most of its start-up (SciPy's optimisation, integration and sparse
packages, the collocation and periodic-orbit code: issue 27), so a package built with
:func:`lazy_exports` imports a sub-module only when one of its names is first asked
for: ``from continuation import System`` loads :mod:`continuation.system` and what it
imports, nothing else. Every public name stays importable as before, and so does every
sub-module as an attribute (``import continuation; continuation.newton``).

A name that is also the name of the sub-module defining it (``continuation.dynamics``'s
function ``simulate`` from its module ``simulate``) stays the name, not the module, as
with eager imports (where the ``from .simulate import simulate`` of the package's
``__init__`` rebinds it): the package's module class then ignores the import system
binding that sub-module to the package.
"""

from __future__ import annotations

import importlib
import sys
import types
from collections.abc import Callable, Iterable, Mapping
from typing import Any


class _Shadowing(types.ModuleType):
    """A package whose public names hide sub-modules of the same name (see module)."""

    _hidden: frozenset[str] = frozenset()

    def __setattr__(self, name: str, value: Any) -> None:
        if name in type(self)._hidden and isinstance(value, types.ModuleType):
            return  # the import system binding the sub-module: keep the public name
        super().__setattr__(name, value)


def lazy_exports(
    package: str, exports: Mapping[str, Iterable[str]]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``__getattr__`` and ``__dir__`` of a package that imports its names on first use.

    Parameters
    ----------
    package : str
        The package's ``__name__``; it must be in :data:`sys.modules` (call from its
        ``__init__``).
    exports : mapping of str to iterable of str
        Sub-module (relative name, e.g. ``"system"`` or ``"sweep.backends"``) to the
        public names it defines.

    Returns
    -------
    getattr_ : callable
        ``getattr_(name)``: the public ``name`` (its sub-module imported on first use
        and the value kept in the package), else the sub-module ``package.name``
        (imported), else :class:`AttributeError`.
    dir_ : callable
        ``dir_()``: the package's attributes and all public names.
    """
    where = {name: sub for sub, names in exports.items() for name in names}
    module = sys.modules[package]
    hidden = frozenset(where) & frozenset(exports)
    if hidden:
        module.__class__ = type("LazyPackage", (_Shadowing,), {"_hidden": hidden})

    def getattr_(name: str) -> Any:
        sub = where.get(name)
        if sub is not None:
            value = getattr(importlib.import_module(f"{package}.{sub}"), name)
            module.__dict__[name] = value  # past the module class's guard
            return value
        if not name.startswith("__"):
            full = f"{package}.{name}"
            try:
                return importlib.import_module(full)
            except ModuleNotFoundError as exc:
                if exc.name != full:
                    raise
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def dir_() -> list[str]:
        return sorted(set(module.__dict__) | set(where))

    return getattr_, dir_


__all__ = ["lazy_exports"]
