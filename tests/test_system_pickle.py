"""A system pickles after its first-use evaluators were built (a continuation ran).

The sudden-change step pickles its periodic orbits with their model; in one process
(``reproduce --workers 1``) that model has already run the equilibria continuations of
the earlier steps. Reference: the unpickled copy evaluates to the same numbers.
"""

from __future__ import annotations

import pickle

import numpy as np

from ship_models import purse_seiner


def test_pickles_after_linearize_and_free_parameter_evaluators() -> None:
    m = purse_seiner()
    x = np.zeros(m.n_states)
    x[m.index("u")] = 7.0
    p = np.asarray(m.default_params().values, dtype=float)
    f0, J0, _ = m.linearize(x, p)
    lin = m.linearizer(m.param_names.index("Fn"), p)
    assert lin is not None and "_ca_lin" in vars(m) and "_ca_lin_free" in vars(m)
    copy = pickle.loads(pickle.dumps(m))
    assert "_ca_lin" not in vars(copy)
    f1, J1, _ = copy.linearize(x, p)  # rebuilt on first use
    np.testing.assert_array_equal(f0, f1)
    np.testing.assert_array_equal(J0, J1)
