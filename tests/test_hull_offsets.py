"""A hull from its offsets: hydrostatics against closed forms, both hull paths meet,
GZ by direct integration, bad input refused in one line."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ship_models import get_vessel_data
from ship_models.contracts import SeaState
from ship_models.estimation import build_vessel_model, form_parameters
from ship_models.hydro.hull import parametric_hull
from ship_models.hydro.hydrostatics import gz_curve
from ship_models.hydro.mesh import check_wetted_mesh, mesh_volume, offsets_panels
from ship_models.hydro.offsets import (
    OffsetsError,
    OffsetsTable,
    form_parameter_offsets,
    hull_from_offsets,
    read_offsets,
    wigley_offsets,
    write_offsets,
)
from ship_models.hydro.upright import check_particulars, hydrostatics
from ship_models.hydro.waves import WaveStrips
from ship_models.vessel import VesselData, VesselFileError, dump_vessel, load_vessel

#: The purse seiner's wave (H/lambda = 1/9.2, lambda/L = 1.5) for the force checks.
SEA = SeaState(1 / 9.2, 1.5)

L, B, T, D = 34.5, 7.0, 2.6, 3.6
WIGLEY = {  # closed forms of the Wigley hull (see wigley_offsets)
    "volume": 4 / 9 * L * B * T,
    "KB": 5 / 8 * T,
    "BM": 3 * B * B / (35 * T),
    "A_wp": 2 / 3 * L * B,
}


def _wigley(n_st: int, n_wl: int):
    t = wigley_offsets(L=L, B=B, T=T, D=D, n_stations=n_st, n_waterlines=n_wl)
    return hull_from_offsets(t, L=L, D=D, d_f=T, d_a=T)


def test_wigley_hydrostatics_converge_to_the_closed_forms_at_second_order():
    """The bilinear surface between offsets errs by O(h^2): halving h quarters the error."""
    errs = []
    for n in ((21, 11), (41, 21), (81, 41)):
        hs = hydrostatics(_wigley(*n))
        assert abs(hs.lcb) < 1e-12 * L
        errs.append(np.array([abs(getattr(hs, k) / v - 1) for k, v in WIGLEY.items()]))
    ratios = errs[0] / errs[1], errs[1] / errs[2]
    for r in ratios:
        np.testing.assert_allclose(r, 4.0, rtol=0.05)
    assert np.all(errs[-1] < 5e-4)


@pytest.fixture(scope="module")
def seiner():
    return get_vessel_data("purse_seiner")


def test_form_parameter_hull_written_as_offsets_gives_the_same_forces(seiner):
    """Particulars-only path (form-parameter strips) and the same hull as offsets meet:
    wave forces and hydrostatics differ by the table's O(h^2) interpolation error."""
    fp = form_parameters(seiner.vessel)
    w0 = seiner.forces.waves
    xi = np.linspace(0.0, 1.0, 16, endpoint=False)
    ref = np.array([w0.forces(s, 8.0, 0.3, SEA, lift=False) for s in xi])
    errs = []
    for n in ((41, 21), (81, 41)):
        t = form_parameter_offsets(fp, n_stations=n[0], n_waterlines=n[1])
        oh = hull_from_offsets(t, L=fp.L, D=fp.D, d_f=fp.d_f, d_a=fp.d_a)
        assert hydrostatics(oh).volume == pytest.approx(seiner.hull.volume, rel=4e-3)
        w1 = WaveStrips.from_hull(oh, x_G=seiner.info["x_G"], zeta_G=seiner.info["zeta_G"],
                                  m22=np.interp(oh.x, seiner.hull.x, w0.m22), z_H=w0.z_H,
                                  rho=w0.rho, g=w0.g, n_depth=8)  # fmt: skip
        got = np.array([w1.forces(s, 8.0, 0.3, SEA, lift=False) for s in xi])
        errs.append(np.max(np.abs(got - ref), axis=0) / np.max(np.abs(ref), axis=0))
    assert np.all(errs[1] < 2e-3)
    assert np.all(errs[1] < 0.35 * errs[0])  # converging (second order: 0.25)


def test_gz_by_direct_integration_of_the_offsets(seiner):
    """GZ of the offsets hull = GZ of the form-parameter hull (same topside), GZ'(0) = GM."""
    fp = form_parameters(seiner.vessel)
    t = form_parameter_offsets(fp, n_stations=81, n_waterlines=61)
    oh = hull_from_offsets(t, L=fp.L, D=fp.D, d_f=fp.d_f, d_a=fp.d_a)
    ph = parametric_hull(fp, n_stations=80)
    GM, top = 1.0, 0.4
    a = gz_curve(oh, GM, topside_height=top)
    b = gz_curve(ph, GM, topside_height=top, n_side=200)
    np.testing.assert_allclose(a.phi, b.phi)
    # same hull by two discretisations (table interpolation O(h^2), polygon sides)
    np.testing.assert_allclose(a.gz, b.gz, atol=5e-3)
    # the computed (not fitted) initial slope is the given GM (KM from the offsets)
    i = int(np.argmax(a.phi > 0))
    assert a.gz[i] / np.sin(a.phi[i]) == pytest.approx(GM, rel=2e-3)


def test_offsets_file_round_trip_and_vessel_path(tmp_path, seiner):
    fp = form_parameters(seiner.vessel)
    t = form_parameter_offsets(fp, n_stations=41, n_waterlines=21)
    p = write_offsets(t, tmp_path / "hull.csv", "test")
    back = read_offsets(p)
    np.testing.assert_allclose(back.y, t.y, atol=1e-6)
    v = load_vessel("purse_seiner")
    meta = dict(v.meta) | {"hull_offsets": "hull.csv"}
    coeffs = dict(v.coefficients) | {"hull.C_wp": seiner.vessel.coefficients["hull.C_wp"]}
    dump_vessel(VesselData("ps_offsets", meta, coeffs), tmp_path / "ps.toml")
    data = build_vessel_model(load_vessel(tmp_path / "ps.toml"))
    assert data.hull.__class__.__name__ == "OffsetsHull"
    assert data.hull.volume == pytest.approx(seiner.hull.volume, rel=5e-3)


# ------------------------------------------------------------------ bad input
def _one_line(exc_info):
    msg = str(exc_info.value)
    assert "\n" not in msg and "np.float64" not in msg
    return msg


def test_bad_offsets_are_refused_in_one_line(tmp_path):
    with pytest.raises(OffsetsError) as e:
        OffsetsTable([0.0, 2.0, 1.0], [0.0, 1.0], np.ones((3, 2)))
    assert "stations must increase" in _one_line(e)
    with pytest.raises(OffsetsError) as e:
        OffsetsTable([0.0, 1.0, 2.0], [0.0, 1.0], [[0, 1], [1, -1], [0, 1]])
    assert "negative half-breadth" in _one_line(e)
    p = tmp_path / "mm.csv"
    t = wigley_offsets(L=L, B=B, T=T, D=D)
    write_offsets(t, p)
    p.write_text(p.read_text().replace("# units = m", "# units = mm"))
    with pytest.raises(OffsetsError) as e:
        hull_from_offsets(read_offsets(p), L=L, D=D, d_f=T, d_a=T)
    assert "units inconsistent" in _one_line(e)
    with pytest.raises(OffsetsError) as e:
        hs = hydrostatics(_wigley(21, 11))
        check_particulars(hs, L=L, B=B, d_m=T, C_b=0.6, lcb_aft=0.0)
    assert "`particulars.C_b` = 0.6 contradicts the hull" in _one_line(e)


def test_vessel_file_with_contradicting_offsets_is_refused(tmp_path):
    write_offsets(wigley_offsets(L=34.5, B=7.6, T=2.65, D=3.07 - 0.01), tmp_path / "w.csv")
    v = load_vessel("purse_seiner")
    meta = dict(v.meta) | {"hull_offsets": "w.csv"}
    dump_vessel(VesselData("bad", meta, dict(v.coefficients)), tmp_path / "bad.toml")
    with pytest.raises(VesselFileError) as e:
        build_vessel_model(load_vessel(tmp_path / "bad.toml"))
    assert _one_line(e).startswith("`vessel.hull_offsets`: `particulars.C_b` = 0.597")


def test_panels_are_closed_outward_and_displace_the_hull():
    h = _wigley(41, 21)
    V, F = offsets_panels(h, nx=40, nz=8)
    check_wetted_mesh(V, F)
    e1 = abs(mesh_volume(V, F) / h.volume - 1)
    V2, F2 = offsets_panels(h, nx=80, nz=16)
    e2 = abs(mesh_volume(V2, F2) / h.volume - 1)
    assert e2 < 0.35 * e1 and e2 < 3e-3  # planar panels on the surface: O(h^2)
    with pytest.raises(OffsetsError) as e:
        check_wetted_mesh(V, F[:, ::-1])
    assert "inverted" in _one_line(e)
    deep = np.argmax(V[F].mean(axis=1)[:, 2] < -0.5 * T)
    with pytest.raises(OffsetsError) as e:
        check_wetted_mesh(V, np.delete(F, deep, axis=0))
    assert "open below the waterline" in _one_line(e)


def test_mesh_volume_of_a_box_is_exact():
    h = hull_from_offsets(
        OffsetsTable([0.0, 5.0, 10.0], [0.0, 2.0], np.full((3, 2), 1.5)), L=10.0, D=3.0,
        d_f=1.0, d_a=1.0,
    )  # fmt: skip
    V, F = offsets_panels(h, nx=4, nz=3)
    check_wetted_mesh(V, F)
    assert mesh_volume(V, F) == pytest.approx(10.0 * 3.0 * 1.0, rel=1e-12)
    assert math.isclose(h.volume, 30.0, rel_tol=1e-12)


def test_capytaine_is_imported_only_for_the_panel_method():
    import subprocess
    import sys

    code = (
        "import sys, ship_models, ship_models.estimation, ship_models.analysis.sensitivity\n"
        "from ship_models import purse_seiner\n"
        "purse_seiner()\n"
        "assert 'capytaine' not in sys.modules, 'capytaine imported'\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_cli_hydrostatics_and_critical_name_the_wave_forces(capsys, tmp_path):
    import json

    from broachkit_cli.main import main

    assert main(["vessels", "hydrostatics", "purse_seiner", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    hs = doc["hydrostatics"]
    assert hs["volume"] == pytest.approx(414.8135, rel=1e-5)
    assert hs["KM"] == pytest.approx(hs["KB"] + hs["BM"])
    assert doc["wave_forces"]["model"] == "froude_krylov_strips"
    assert doc["gz"]["max_gz_m"] > 0
    assert main(["vessels", "hydrostatics", str(tmp_path / "none.toml")]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert main(["critical", "--chi-c", "10", "--method", "bvp", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["wave_force_model"] == "froude_krylov_strips"
    assert doc["Fn"] == pytest.approx(0.30161168, abs=1e-7)
