"""The one-page vessel report (studies/vessel_report.py) and the study helpers (_common)."""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import numpy as np
import pytest

STUDIES = Path(__file__).resolve().parents[1] / "studies"


@pytest.fixture(scope="module")
def studies_path():
    sys.path.insert(0, str(STUDIES))
    yield
    sys.path.remove(str(STUDIES))


@pytest.fixture(scope="module")
def vr(studies_path):
    import vessel_report

    return vessel_report


@pytest.fixture(scope="module")
def common(studies_path):
    import _common

    return _common


@pytest.fixture(scope="module")
def report(vr, tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    return vr.build_report("purse_seiner", out)


@pytest.fixture(scope="module")
def data():
    from ship_models import get_vessel_data

    return get_vessel_data("purse_seiner")


def test_files_written(report):
    import matplotlib.image as mpimg

    for f in (
        report.png,
        report.particulars,
        report.coefficients,
        report.gz,
        report.resistance_thrust,
        report.wave_amplitudes,
    ):
        assert f.is_file() and f.stat().st_size > 200, f
        assert f.name.startswith("purse_seiner_")
    img = mpimg.imread(report.png)
    h, w = img.shape[:2]
    assert w > 1500 and h > 1500  # one page at 150 dpi
    assert np.std(img[..., :3]) > 0.05  # not blank


def test_coefficient_table_is_the_resolved_vessel(report, data):
    with report.coefficients.open() as fh:
        rows = list(csv.DictReader(line for line in fh if not line.startswith("#")))
    assert {r["key"] for r in rows} == set(data.vessel.coefficients)
    for r in rows:
        c = data.vessel.coefficient(r["key"])
        assert float(r["value"]) == c.value and r["unit"] == c.unit
        assert r["status"] == c.status and r["source"] == c.source


def test_gz_table(report, common, data):
    t = common.read_csv(report.gz)
    GM = data.vessel.get("loading.GM")
    phi = np.deg2rad(t["phi_deg"])
    # fit has GZ'(0) = GM: GZ(1 deg) = GM sin-series ~ GM phi (within the curvature term)
    k = int(np.argmin(np.abs(t["phi_deg"] - 1.0)))
    assert t["gz_fit_m"][k] / phi[k] == pytest.approx(GM, rel=2e-3)
    assert t["gz_hydrostatic_m"][0] == 0.0 and t["gz_hydrostatic_m"][-1] == 0.0
    np.testing.assert_allclose(t["gz_hydrostatic_m"], data.gz.gz, rtol=0, atol=1e-15)
    assert np.max(np.abs(t["gz_fit_m"] - t["gz_hydrostatic_m"])) == pytest.approx(
        data.info["gz_fit_error"], rel=1e-12
    )


def test_resistance_and_thrust_balance_at_the_commanded_speeds(report, common, data):
    """Each thrust curve T(u; n(Fn_k)) crosses R(u) at u = Fn_k sqrt(g L) (by definition of
    n(Fn)): the crossing found in the table lies within one grid step of Fn_k."""
    t = common.read_csv(report.resistance_thrust)
    Fn, R = t["Fn"], t["R_model_N"]
    cols = [k for k in t if k.startswith("T_Fn")]
    assert len(cols) >= 3
    dFn = Fn[1] - Fn[0]
    for col in cols:
        Fn_k = float(col[4:8])
        gap = t[col] - R
        i = np.nonzero(np.diff(np.sign(gap)))[0]
        assert i.size == 1, col
        j = i[0]
        cross = Fn[j] - gap[j] * dFn / (gap[j + 1] - gap[j])
        assert abs(cross - Fn_k) < dFn, col
    # the model's resistance is the spline of the Holtrop-Mennen formula (max error reported)
    m = Fn > 0.1
    rel = np.abs(R[m] - t["R_holtrop_N"][m]) / t["R_holtrop_N"][m]
    assert np.max(rel) <= data.info["resistance_fit_error"] * 1.0001 + 1e-12


def test_wave_amplitudes(report, common, vr, data):
    t = common.read_csv(report.wave_amplitudes)
    chi = t["chi_deg"]
    i0 = int(np.argmin(np.abs(chi)))
    # head/following seas: no lateral forces by port-starboard symmetry
    scale = np.max(t["Y_amp_N"])
    assert t["Y_amp_N"][i0] < 1e-9 * scale and t["K_amp_Nm"][i0] < 1e-9 * np.max(t["K_amp_Nm"])
    # beam seas: the Froude-Krylov surge force vanishes (cos chi factor)
    i90 = int(np.argmin(np.abs(chi - 90.0)))
    assert t["X_fk_amp_N"][i90] < 1e-9 * np.max(t["X_fk_amp_N"])
    # amplitude from two phases = maximum over a fine xi grid (independent evaluation)
    from ship_models.contracts import SeaState

    F = data.forces
    Hl, lL = data.vessel.get("waves.H_over_lambda"), data.vessel.get("waves.lambda_over_L")
    sea = SeaState(Hl, lL)
    c = float(F.celerity(lL))
    xi = np.linspace(0.0, 1.0, 4001)
    for ang in (0.0, 30.0, 65.0):
        k = int(np.argmin(np.abs(chi - ang)))
        series = np.array([F.waves.forces(s, c, np.deg2rad(ang), sea) for s in xi])
        brute = np.max(np.abs(series), axis=0)
        row = np.array([t["X_amp_N"][k], t["Y_amp_N"][k], t["N_amp_Nm"][k], t["K_amp_Nm"][k]])
        big = brute > 1e-9 * np.max(brute)
        np.testing.assert_allclose(row[big], brute[big], rtol=2e-6)


def test_kvlcc2_report_and_command_line(vr, tmp_path, capsys):
    assert vr.main(["kvlcc2", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "kvlcc2_report.png" in out
    assert (tmp_path / "kvlcc2_resistance_thrust.csv").is_file()
    with (tmp_path / "kvlcc2_resistance_thrust.csv").open() as fh:
        meta = [line for line in fh if line.startswith("#")]
    assert any("R0'" in line for line in meta)  # MMG resistance, not the Holtrop spline
    assert vr.main(["no_such_vessel", "--out", str(tmp_path)]) == 2
    assert "unknown model" in capsys.readouterr().err


def test_commanded_froude_numbers(vr):
    np.testing.assert_allclose(vr.commanded_froude_numbers(0.4886), [0.12, 0.24, 0.37, 0.49])


# ---------------------------------------------------------------------- _common
def test_csv_round_trip_and_bad_input(common, tmp_path):
    a = np.array([0.1, 1.0 / 3.0, -2.5e-17, np.pi])
    f = common.save_csv(tmp_path / "x.csv", {"a": a, "b": 2 * a}, meta={"unit": "m"})
    assert f.read_text().startswith("# unit: m\n")
    back = common.read_csv(f)
    assert list(back) == ["a", "b"]
    np.testing.assert_array_equal(back["a"], a)  # full precision
    np.testing.assert_array_equal(back["b"], 2 * a)
    with pytest.raises(ValueError, match=r"columns\['b'\]"):
        common.save_csv(tmp_path / "y.csv", {"a": a, "b": a[:2]})
    with pytest.raises(ValueError, match="columns"):
        common.save_csv(tmp_path / "y.csv", {})
    with pytest.raises(ValueError, match=r"rows\[1\]"):
        common.save_table(tmp_path / "t.csv", ("k", "v"), [("a", 1.0), ("b",)])


def test_output_dir_and_figure(common, tmp_path, monkeypatch):
    monkeypatch.setenv(common.OUT_ENV, str(tmp_path / "env_root"))
    d = common.output_dir("study")
    assert d == tmp_path / "env_root" / "study" and d.is_dir()
    assert common.output_dir("s2", root=tmp_path) == tmp_path / "s2"
    with common.figure_style():
        fig = common.new_figure((3.0, 2.0))
        ax = fig.add_subplot()
        ax.plot([0, 1], [0, 1])
        p = common.save_figure(fig, tmp_path / "fig" / "line")
    assert p.name == "line.png" and p.is_file()
