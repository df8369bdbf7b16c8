"""Branch results: row/column views, files, plotting; equilibria helpers and eigen-data."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from helpers import brusselator, cstr, fold_normal_form, hopf_normal_form, periodic_sine  # noqa: E402

from continuation.api import continue_equilibria  # noqa: E402
from continuation.branch import Branch, SpecialKind, SpecialPoint  # noqa: E402
from continuation.equilibria import solve_equilibrium, unique_equilibria  # noqa: E402
from continuation.errors import ConvergenceError  # noqa: E402
from continuation.events import Event  # noqa: E402
from continuation.plotting import plot_branch  # noqa: E402
from continuation.problem import EquilibriumProblem  # noqa: E402
from continuation.stability import count_unstable, eigen, eigenvalues  # noqa: E402
from continuation.status import Status  # noqa: E402


@pytest.fixture(scope="module")
def cstr_branch():
    ev = Event("u1_half", lambda x, p: x[0] - 0.5)
    return continue_equilibria(
        cstr(),
        [0.0, 0.0],
        {"Da": 0.0},
        "Da",
        p_min=0.0,
        p_max=0.4,
        events=[ev],
        direction="forward",
    )


def test_views(cstr_branch):
    br = cstr_branch
    N = len(br)
    assert br.x.shape == (N, 2) and br.p.shape == (N,) and br.eigenvalues.shape == (N, 2)
    assert br.state_names == ("u1", "u2")
    np.testing.assert_array_equal(br.state("u2"), br.x[:, 1])
    np.testing.assert_array_equal(br.param("Da"), br.p)
    np.testing.assert_array_equal(br.param("B"), np.full(N, 14.0))
    row = br[5]
    assert row.index == 5 and row.p == br.p[5] and row.stable == bool(br.stable[5])
    np.testing.assert_array_equal(row.x, br.x[5])
    assert br[-1].p == br.p[-1]
    with pytest.raises(IndexError):
        br[N]
    with pytest.raises(ValueError, match="u3"):
        br.state("u3")
    with pytest.raises(ValueError, match="Dx"):
        br.param("Dx")
    # eigenvalues sorted by decreasing real part; stability consistent with them
    re = br.eigenvalues.real
    assert np.all(np.diff(re, axis=1) <= 0)
    np.testing.assert_array_equal(br.stable, np.all(re <= 1e-10, axis=1))
    for k in range(N):
        nr, nc = count_unstable(br.eigenvalues[k])
        assert br.n_unstable[k] == nr + 2 * nc
    # find by kind (enum or string) and by event name
    assert br.find("fold") == br.find(SpecialKind.FOLD) and len(br.find("fold")) == 2
    (e,) = br.find("u1_half")
    assert e.kind is SpecialKind.USER and e.x[0] == pytest.approx(0.5, abs=1e-10)
    with pytest.raises(ValueError, match="kind"):
        br.find("hopff")
    assert [sp.label for sp in br.special_points] == sorted(
        [sp.label for sp in br.special_points], key=[sp.label for sp in br.special_points].index
    )
    assert {sp.label for sp in br.find("fold")} == {"F1", "F2"}
    # arrays are read-only
    with pytest.raises(ValueError):
        br.p[0] = 1.0


def test_save_load_round_trip(cstr_branch, tmp_path):
    br = cstr_branch
    path = br.save(tmp_path / "cstr")
    assert path.suffix == ".npz" and path.with_suffix(".json").exists()
    br2 = Branch.load(tmp_path / "cstr.npz")
    assert br2.problem is None
    for name in ("p", "x", "eigenvalues", "n_unstable", "ds", "newton_iters"):
        np.testing.assert_array_equal(getattr(br2, name), getattr(br, name))
    assert br2.status is br.status and br2.message == br.message and br2.free == "Da"
    assert br2.settings == br.settings
    assert br2.state_names == br.state_names and br2.param_values == br.param_values
    np.testing.assert_array_equal(br2.param("beta"), br.param("beta"))
    assert len(br2.special_points) == len(br.special_points)
    for a, b in zip(br.special_points, br2.special_points, strict=True):
        assert (a.kind, a.index, a.p, a.located, a.bracket, a.label, a.s) == (
            b.kind,
            b.index,
            b.p,
            b.located,
            b.bracket,
            b.label,
            b.s,
        )
        np.testing.assert_array_equal(a.x, b.x)
        assert dict(a.data) == dict(b.data)
    assert br2.find("u1_half")
    prob = EquilibriumProblem(cstr(), cstr().params(), "Da")
    assert Branch.load(path, problem=prob).problem is prob
    with pytest.raises(ValueError, match="path"):
        Branch.load(tmp_path / "missing.npz")


def test_save_load_default_bounds(tmp_path):
    br = continue_equilibria(fold_normal_form(), [1.0], {"mu": 1.0}, "mu", max_steps=20)
    assert br.settings.p_min == -np.inf
    br2 = Branch.load(br.save(tmp_path / "fold.npz"))
    assert br2.settings == br.settings and br2.status is Status.MAX_STEPS
    assert br2.event_names == () and len(br2.find("fold")) == len(br.find("fold")) == 1


def test_csv_round_trip(cstr_branch, tmp_path):
    br = cstr_branch
    path = br.to_csv(tmp_path / "cstr.csv")
    header = path.read_text().splitlines()[0].split(",")
    assert header[:3] == ["Da", "u1", "u2"]
    data = np.genfromtxt(path, delimiter=",", names=True)
    assert len(data) == len(br)
    np.testing.assert_array_equal(data["Da"], br.p)
    np.testing.assert_array_equal(data["u2"], br.state("u2"))
    np.testing.assert_array_equal(data["n_unstable"], br.n_unstable)
    np.testing.assert_array_equal(data["eig0_re"], br.eigenvalues[:, 0].real)
    np.testing.assert_array_equal(data["eig1_im"], br.eigenvalues[:, 1].imag)


def test_plot_branch_styles():
    br = continue_equilibria(fold_normal_form(), [1.0], {"mu": 1.0}, "mu", p_max=2.0)
    fig, ax = plt.subplots()
    artists = plot_branch(ax, br, y="x")
    lines = [a for a in artists if hasattr(a, "get_linestyle") and len(a.get_xdata()) > 1]
    styles = {ln.get_linestyle() for ln in lines}
    assert styles == {"-", "--"}
    # rows run from x < 0 (unstable, dashed) to x > 0 (stable, solid); consecutive
    # segments share their joining row
    dashed, solid = lines
    assert dashed.get_linestyle() == "--" and solid.get_linestyle() == "-"
    assert np.all(np.asarray(dashed.get_ydata())[:-1] < 0)
    assert np.all(np.asarray(solid.get_ydata()) > 0)
    assert dashed.get_ydata()[-1] == solid.get_ydata()[0]
    assert len(dashed.get_ydata()) + len(solid.get_ydata()) == len(br) + 1
    texts = [a.get_text() for a in artists if hasattr(a, "get_text")]
    assert texts == ["F1"]
    assert ax.get_xlabel() == "mu"
    plot_branch(ax, br, y=lambda x, p: x[0] ** 2, x="x")
    with pytest.raises(ValueError, match="coordinate"):
        plot_branch(ax, br, y="nope")
    plt.close(fig)


def test_eigen_vectors_and_values():
    sys = brusselator()
    par = sys.params(A=1.0, B=2.5)
    x = np.array([1.0, 2.5])
    res = eigen(sys, x, par, vectors=True)
    J = sys.jacobian(x, sys.check_params(par))
    for k in range(2):
        np.testing.assert_allclose(
            J @ res.vectors[:, k], res.values[k] * res.vectors[:, k], atol=1e-12
        )
    # trace = B - 1 - A^2 = 0.5 > 0 and det = A^2 = 1: unstable focus
    assert res.n_unstable == 2 and not res.stable
    np.testing.assert_allclose(res.values.real, 0.25, atol=1e-12)
    prob = EquilibriumProblem(sys, par, "B")
    np.testing.assert_allclose(eigen(prob, x, 2.5, vectors=False).values, res.values)
    np.testing.assert_allclose(eigenvalues(J), res.values)


def test_solve_equilibrium_and_failure():
    sys = hopf_normal_form()
    res = solve_equilibrium(sys, [0.1, -0.05], {"mu": -0.5})
    assert res.converged and res.status is Status.SUCCESS
    np.testing.assert_allclose(res.x, 0.0, atol=1e-12)
    np.testing.assert_allclose(res.eigenvalues, [-0.5 + 1j, -0.5 - 1j], atol=1e-12)
    assert res.stable and res.n_unstable == 0 and res.params["mu"] == -0.5
    fold = fold_normal_form()
    with pytest.raises(ConvergenceError):
        solve_equilibrium(fold, [1.0], {"mu": -1.0})  # no real equilibrium
    bad = solve_equilibrium(fold, [1.0], {"mu": -1.0}, throw=False)
    assert not bad.converged and not bad.stable and bad.n_unstable == -1


def test_unique_equilibria_modulo_period():
    sys = periodic_sine()
    two_pi = 2 * np.pi
    pts = [[0.5], [0.5 + two_pi], [np.pi - 0.5], [0.5 - 2 * two_pi + 1e-9], [np.pi - 0.5]]
    uniq = unique_equilibria(sys, pts, tol=1e-6)
    np.testing.assert_allclose(uniq, [[0.5], [np.pi - 0.5]])
    assert unique_equilibria(sys, [], 1e-6).shape == (0, 1)
    with pytest.raises(ValueError, match="points"):
        unique_equilibria(sys, [[0.0, 1.0]], 1e-6)


def test_failing_start_gives_status_or_raises():
    fold = fold_normal_form()
    br = continue_equilibria(fold, [1.0], {"mu": -1.0}, "mu")
    assert br.status is Status.NEWTON_FAILED and len(br) == 0 and not br.status.ok
    assert "start point" in br.message
    with pytest.raises(ConvergenceError):
        continue_equilibria(fold, [1.0], {"mu": -1.0}, "mu", throw=True)


def test_sort_and_count_eigenvalues():
    """Sorting (decreasing real part, then imaginary part, NaN last) and the saddle
    index agree with a direct count, on both the small (pure Python) and the large
    (NumPy) path."""
    from continuation.stability import count_unstable, sort_eigenvalues

    rng = np.random.default_rng(0)
    for n in (3, 12, 40, 80):
        re = rng.standard_normal(n)
        im = rng.standard_normal(n) * (rng.random(n) < 0.5)
        v = np.concatenate([re + 1j * im, re - 1j * im])
        v[0] = np.nan
        s = sort_eigenvalues(rng.permutation(v))
        assert np.isnan(s[-1])
        fin = s[:-1]
        assert np.all(np.diff(fin.real) <= 0)
        ties = np.diff(fin.real) == 0
        assert np.all(np.diff(fin.imag)[ties] <= 0)
        nr = int(np.sum((v.real > 1e-10) & (np.abs(v.imag) <= 1e-8 * np.maximum(1, abs(v)))))
        npairs = int(np.sum((v.real > 1e-10) & (v.imag > 1e-8 * np.maximum(1, abs(v)))))
        assert count_unstable(v) == count_unstable(s) == (nr, npairs)


@pytest.mark.parametrize("cycles", [True, False])
def test_load_version_1_cycle_points(cstr_branch, tmp_path, cycles):
    """Version-1 files stored PD/NS of cycle branches as ``user`` points: they load as
    the ``pd``/``ns`` kinds (found by kind and by label); a user event named "PD" on a
    branch without periods stays a user point."""
    import dataclasses
    import json

    br = cstr_branch
    pts = tuple(
        SpecialPoint(SpecialKind.USER, 1, float(br.p[1]), br.x[1], True, (0.0, 1.0), label=lab)
        for lab in ("PD", "NS")
    )
    records = {**br.records, "T": np.ones(len(br))} if cycles else dict(br.records)
    old = dataclasses.replace(br, special_points=pts, records=records)
    js = old.save(tmp_path / "old").with_suffix(".json")
    meta = json.loads(js.read_text())
    assert meta["version"] == 2
    js.write_text(json.dumps({**meta, "version": 1}))
    new = Branch.load(js.with_suffix(".npz"))
    if cycles:
        assert [s.kind for s in new.special_points] == [
            SpecialKind.PERIOD_DOUBLING,
            SpecialKind.NEIMARK_SACKER,
        ]
        assert new.find("pd") == new.find("PD") and len(new.find("ns")) == 1
    else:
        assert all(s.kind is SpecialKind.USER for s in new.special_points)
        assert new.find("pd") == () and len(new.find("PD")) == 1
    # version 2 round trip keeps the kinds as written
    again = Branch.load(new.save(tmp_path / "new"))
    assert [s.kind for s in again.special_points] == [s.kind for s in new.special_points]
