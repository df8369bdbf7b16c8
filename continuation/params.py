"""Named parameter vectors."""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from .typing import FloatArray


def name_index(names: Sequence[str], name: str, what: str) -> int:
    """Position of ``name`` in ``names``.

    Raises
    ------
    ValueError
        ``unknown <what> name ...; valid names are ...`` when ``name`` is not there.
    """
    try:
        return names.index(name)
    except ValueError:
        raise ValueError(f"unknown {what} name {name!r}; valid names are {names}") from None


@dataclass(frozen=True, eq=False)
class Params(Mapping[str, float]):
    """An immutable vector of named parameters.

    Parameters
    ----------
    names : tuple of str
        Parameter names, shape ``(m,)``.
    values : array_like, shape (m,)
        Parameter values, in the order of ``names``. Stored as a read-only copy.

    Examples
    --------
    >>> p = Params(("a", "b"), [1.0, 2.0])
    >>> p["b"], p.replace(a=3.0)["a"]
    (2.0, 3.0)
    """

    names: tuple[str, ...]
    # (the array of values shadows Mapping.values(), the documented API of Params)
    values: FloatArray = field(repr=False)  # type: ignore[assignment]

    def __post_init__(self) -> None:
        names = tuple(str(n) for n in self.names)
        if len(set(names)) != len(names):
            raise ValueError(f"`names` must be unique, got {names}")
        vals = np.array(self.values, dtype=float).reshape(-1)
        if vals.shape != (len(names),):
            raise ValueError(
                f"`values` must have shape ({len(names)},) to match `names`, got {vals.shape}"
            )
        vals.setflags(write=False)
        object.__setattr__(self, "names", names)
        object.__setattr__(self, "values", vals)

    @classmethod
    def from_mapping(cls, names: Sequence[str], mapping: Mapping[str, float]) -> Params:
        """Build from a mapping that must name every parameter in ``names``.

        Raises
        ------
        ValueError
            If a name is missing, unknown, or a value is not finite.
        """
        names = tuple(names)
        unknown = sorted(set(mapping) - set(names))
        if unknown:
            raise ValueError(f"unknown parameter name(s) {unknown}; valid names are {names}")
        missing = [n for n in names if n not in mapping]
        if missing:
            raise ValueError(f"missing value(s) for parameter(s) {missing}")
        vals = [float(mapping[n]) for n in names]
        bad = [n for n, v in zip(names, vals, strict=True) if not np.isfinite(v)]
        if bad:
            raise ValueError(f"parameter(s) {bad} must be finite")
        return cls(names, np.array(vals))

    def index(self, name: str) -> int:
        """Position of parameter ``name``; raises ValueError listing valid names."""
        return name_index(self.names, name, "parameter")

    def __getitem__(self, name: str) -> float:
        return float(self.values[self.index(name)])

    def __iter__(self) -> Iterator[str]:
        return iter(self.names)

    def __len__(self) -> int:
        return len(self.names)

    def replace(self, **changes: float) -> Params:
        """Return a copy with some values changed; unknown names raise ValueError."""
        vals = np.array(self.values, dtype=float)
        for k, v in changes.items():
            fv = float(v)
            if not np.isfinite(fv):
                raise ValueError(f"parameter {k!r} must be finite, got {v}")
            vals[self.index(k)] = fv
        return Params(self.names, vals)

    def with_vector(self, values: FloatArray) -> Params:
        """Return a copy with all values replaced by ``values`` (shape ``(m,)``)."""
        return Params(self.names, values)

    def as_dict(self) -> dict[str, float]:
        """Plain ``{name: value}`` dictionary."""
        return {n: float(v) for n, v in zip(self.names, self.values, strict=True)}

    def __repr__(self) -> str:
        inner = ", ".join(f"{n}={v:.6g}" for n, v in self.as_dict().items())
        return f"Params({inner})"


__all__ = ["Params", "name_index"]
