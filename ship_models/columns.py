"""CSV columns of the ship's states, in one unit convention for every output.

Angles (``chi``, ``phi``, ``delta``) are written in degrees as ``<name>_deg``, angular
rates (``r``, ``p_roll``) in degrees per second as ``<name>_deg_s``; the other states
as they are (SI units, ``xi_G`` in wavelengths). The studies' CSVs and the command
line's ``periodic.csv`` both use :func:`state_columns`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

#: States that are angles (written in degrees, ``<name>_deg``).
ANGLE_STATES = ("chi", "phi", "delta")
#: States that are angular rates (written in deg/s, ``<name>_deg_s``).
RATE_STATES = ("r", "p_roll")


def state_columns(names: Sequence[str], x: np.ndarray) -> dict[str, np.ndarray]:
    """CSV columns of states ``x``, shape ``(N, n)``: angles in degrees, rates in deg/s.

    Parameters
    ----------
    names : sequence of str
        The ``n`` state names, in the order of the columns of ``x``.
    x : ndarray, shape (N, n)
        States at ``N`` samples (a single state of shape ``(n,)`` is one row).

    Returns
    -------
    dict of str to ndarray, each of shape (N,)
        ``chi_deg``, ``phi_deg``, ``delta_deg``, ``r_deg_s``, ``p_roll_deg_s`` and the
        other states under their own names, in the order of ``names``.
    """
    x = np.atleast_2d(np.asarray(x, dtype=float))
    cols: dict[str, np.ndarray] = {}
    for k, n in enumerate(names):
        if n in ANGLE_STATES:
            cols[f"{n}_deg"] = np.degrees(x[:, k])
        elif n in RATE_STATES:
            cols[f"{n}_deg_s"] = np.degrees(x[:, k])
        else:
            cols[n] = x[:, k]
    return cols


__all__ = ["ANGLE_STATES", "RATE_STATES", "state_columns"]
