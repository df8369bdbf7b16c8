"""Wave forces by the panel method (Capytaine): Froude-Krylov part against the strips,
diffraction against MacCamy & Fuchs' closed form, mesh convergence, and the tabulated
model through the whole chain (fit, phase, CasADi right-hand side, critical Fn)."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("capytaine")

from ship_models import get_vessel_data  # noqa: E402
from ship_models.analysis.critical_bvp import critical_fn_bvp  # noqa: E402
from ship_models.contracts import SeaState, wave_model_name  # noqa: E402
from ship_models.estimation import form_parameters  # noqa: E402
from ship_models.hydro.mesh import offsets_panels  # noqa: E402
from ship_models.hydro.offsets import form_parameter_offsets, hull_from_offsets  # noqa: E402
from ship_models.hydro.panel import PanelTable, PanelWaves, panel_table  # noqa: E402
from ship_models.hydro.waves import WaveStrips, strip_waves  # noqa: E402
from ship_models.umeda_4dof import Umeda4DOF  # noqa: E402

LL, HL = 1.5, 1 / 9.2


@pytest.fixture(scope="module")
def seiner():
    return get_vessel_data("purse_seiner")


@pytest.fixture(scope="module")
def hull(seiner):
    fp = form_parameters(seiner.vessel)
    t = form_parameter_offsets(fp, n_stations=81, n_waterlines=41)
    return hull_from_offsets(t, L=fp.L, D=fp.D, d_f=fp.d_f, d_a=fp.d_a)


@pytest.fixture(scope="module")
def strips(seiner, hull):
    w0 = seiner.forces.waves
    return WaveStrips.from_hull(hull, x_G=seiner.info["x_G"], zeta_G=seiner.info["zeta_G"],
                                m22=np.interp(hull.x, seiner.hull.x, w0.m22), z_H=w0.z_H,
                                rho=w0.rho, g=w0.g, n_depth=8)  # fmt: skip


def _series(amp, a, xi):
    return np.array([[-a * np.real(amp[n] * np.exp(2j * np.pi * s)) for n in range(4)] for s in xi])


@pytest.mark.parametrize(("nx", "nz", "tol"), [(50, 10, (0.01, 0.01, 0.01, 0.03)),
                                               (80, 16, (0.004, 0.004, 0.004, 0.01))])  # fmt: skip
def test_froude_krylov_part_equals_the_strip_integration(seiner, hull, strips, nx, nz, tol):
    """Capytaine's Froude-Krylov force on the panels of the same hull = the strips
    (X, Y, N within 1 % on 1,000 panels; the roll moment converges more slowly, 2 %
    -> 0.8 % from 1,000 to 2,560 panels). No BEM solve (pressure integration only)."""
    V, F = offsets_panels(hull, nx=nx, nz=nz)
    tab = panel_table(V, F, L=hull.L, x_G=seiner.info["x_G"], zeta_G=seiner.info["zeta_G"],
                      rho=strips.rho, g=strips.g, lambda_over_L=[LL], chi_deg=[0.0, 30.0],
                      solve=False, cache=False)  # fmt: skip
    a = 0.5 * HL * LL * hull.L
    xi = np.linspace(0.0, 1.0, 64, endpoint=False)
    for j, chi in ((0, 0.0), (1, math.radians(30.0))):
        ref = np.array([strips.forces(s, 8.0, chi, SeaState(HL, LL), lift=False) for s in xi])
        got = _series(tab.fk[:, 0, j], a, xi)
        scale = np.abs(ref).max(axis=0)
        n = 1 if chi == 0 else 4  # at chi = 0 only the surge force is not zero
        err = np.abs(got - ref).max(axis=0)[:n] / scale[:n]
        assert np.all(err < np.array(tol)[:n]), (chi, err)


def _maccamy_fuchs(resolution, ka, h=2.0, a=1.0, rho=1000.0, g=9.81):
    import capytaine as cpt
    from capytaine.bem.airy_waves import froude_krylov_force
    from scipy.special import jvp, yvp

    mesh = cpt.mesh_vertical_cylinder(length=h, radius=a, center=(0, 0, -h / 2),
                                      resolution=resolution)  # fmt: skip
    body = cpt.FloatingBody(mesh=mesh, dofs=cpt.rigid_body_dofs(rotation_center=(0, 0, 0)))
    k = ka / a
    omega = math.sqrt(g * k * math.tanh(k * h))
    pb = cpt.DiffractionProblem(body=body, omega=omega, wave_direction=0.0, water_depth=h,
                                rho=rho, g=g)  # fmt: skip
    res = cpt.BEMSolver().solve(pb)
    F = abs(res.forces["Surge"] + froude_krylov_force(pb)["Surge"])
    # MacCamy, R.C. & Fuchs, R.A. 1954, "Wave forces on piles: a diffraction theory",
    # Beach Erosion Board Tech. Memo 69: |F| = 4 rho g A tanh(kh) / (k^2 |H_1'(ka)|)
    ref = 4 * rho * g * math.tanh(k * h) / (k * k * abs(jvp(1, ka) + 1j * yvp(1, ka)))
    return F / ref - 1.0


@pytest.mark.parametrize("ka", [1.0, 2.0])
def test_diffraction_of_a_vertical_cylinder_matches_maccamy_fuchs(ka):
    """Bottom-mounted vertical cylinder (192 panels): the exciting force within 1.5 %
    of the closed form (the diffraction being half the force at ka = 1)."""
    assert abs(_maccamy_fuchs((0, 24, 8), ka)) < 0.015


@pytest.mark.slow
@pytest.mark.parametrize("ka", [0.5, 1.0, 2.0])
def test_maccamy_fuchs_error_falls_with_the_mesh(ka):
    e1 = abs(_maccamy_fuchs((0, 24, 8), ka))
    e2 = abs(_maccamy_fuchs((0, 48, 16), ka))
    assert e2 < 0.75 * e1 and e2 < 0.013


@pytest.mark.slow
def test_hull_diffraction_ratio_on_two_meshes(seiner, hull):
    """The surge ratio |FK + D| / |FK| at lambda/L = 1.5 on 640 and 1,000 panels agrees
    to 1 % (0.82-0.83 for this hull at zero speed)."""
    out = []
    for nx, nz in ((40, 8), (50, 10)):
        V, F = offsets_panels(hull, nx=nx, nz=nz)
        tab = panel_table(V, F, L=hull.L, x_G=seiner.info["x_G"], zeta_G=seiner.info["zeta_G"],
                          rho=1025.0, g=9.80665, lambda_over_L=[LL], chi_deg=[0.0, 20.0],
                          cache=False)  # fmt: skip
        out.append(tab.amplitude_ratio(0)[0])
    np.testing.assert_allclose(out[0], out[1], rtol=0.01)
    assert np.all((out[1] > 0.7) & (out[1] < 0.95))


def _strip_table(strips: WaveStrips, lL, chi_deg) -> PanelTable:
    """The strips' own Froude-Krylov amplitudes in the table format (no BEM)."""
    fk = np.zeros((4, len(lL), len(chi_deg)), dtype=complex)
    for i, r in enumerate(lL):
        a = 0.5 * HL * r * strips.L
        for j, c in enumerate(chi_deg):
            chi = math.radians(c)
            f0 = np.array(strips.forces(0.0, 0.0, chi, SeaState(HL, r), lift=False))
            f1 = np.array(strips.forces(0.25, 0.0, chi, SeaState(HL, r), lift=False))
            fk[:, i, j] = (-f0 + 1j * f1) / a  # X(s) = -a Re[F e^{2 pi i s}]
    return PanelTable(np.array(lL), np.radians(chi_deg), fk, np.zeros_like(fk), strips.L)


def test_tabulated_model_reproduces_the_strips_through_the_whole_chain(seiner):
    """A table of the strips' own amplitudes, fitted and evaluated by PanelWaves inside
    the CasADi right-hand side, gives the strips' forces and the same critical Fn."""
    w0 = seiner.forces.waves
    lL = np.linspace(1.0, 3.0, 21)
    chi_deg = np.arange(0.0, 61.0, 10.0)
    pw = PanelWaves.from_table(_strip_table(w0, lL, chi_deg), w0, diffraction=False)
    assert pw.fit_error < 1e-3
    for s, chi, r in ((0.3, 0.17, 1.5), (0.8, 0.5, 2.2), (0.1, 0.0, 1.13)):
        sea = SeaState(HL, r)
        np.testing.assert_allclose(pw.forces(s, 8.0, chi, sea), w0.forces(s, 8.0, chi, sea),
                                   rtol=0, atol=2e-3 * 8e5)  # fmt: skip
    assert pw.in_range(1.5, 0.17) and not pw.in_range(3.5, 0.17)

    def builder(inputs):
        return PanelWaves.from_table(_strip_table(strip_waves(inputs), lL, chi_deg),
                                     strip_waves(inputs), diffraction=False)  # fmt: skip

    m = Umeda4DOF(seiner.vessel.path or "purse_seiner", waves=builder)
    assert wave_model_name(m) == "panel_fk"
    ref = critical_fn_bvp(math.radians(10.0), model=Umeda4DOF(seiner))
    got = critical_fn_bvp(math.radians(10.0), model=m)
    assert got.success and ref.success
    # the fit's force error (< 1e-3 of the amplitude) moves Fn* by ~dFn/dX_w * 1e-3
    assert abs(got.Fn - ref.Fn) < 2e-4


def test_mesh_file_round_trip_and_bad_meshes(tmp_path, hull):
    """A hull mesh file (GDF, read by Capytaine) is clipped at the waterline and checked:
    the same volume back; an inverted mesh, a hole, wrong units, a contradicting volume
    are refused in one line."""
    from ship_models.hydro.mesh import mesh_volume
    from ship_models.hydro.offsets import OffsetsError
    from ship_models.hydro.panel import read_hull_mesh, write_gdf

    V, F = offsets_panels(hull, nx=30, nz=6)
    vol = mesh_volume(V, F)
    p = write_gdf(V, F, tmp_path / "hull.gdf")
    V2, F2 = read_hull_mesh(p, L=hull.L, volume=vol)
    assert mesh_volume(V2, F2) == pytest.approx(vol, rel=1e-9)
    bad = {
        "inverted": (V, F[:, ::-1]),
        "open below the waterline": (V, np.delete(F, len(F) // 3, axis=0)),
    }
    for what, (v, f) in bad.items():
        with pytest.raises(OffsetsError) as e:
            read_hull_mesh(write_gdf(v, f, tmp_path / "bad.gdf"))
        assert what in str(e.value) and "\n" not in str(e.value)
    with pytest.raises(OffsetsError, match="units inconsistent"):
        read_hull_mesh(write_gdf(V * 1000.0, F, tmp_path / "mm.gdf"), L=hull.L)
    with pytest.raises(OffsetsError, match="particulars give"):
        read_hull_mesh(p, volume=1.1 * vol)


def test_vessel_file_with_a_mesh_and_panel_froude_krylov(tmp_path, seiner):
    """[vessel] hull_mesh + wave_forces = panel_fk: the model's wave forces come from the
    mesh file (Froude-Krylov only: no BEM solve) and match the strips; a mesh without a
    panel method is refused."""
    from ship_models.contracts import wave_model_name
    from ship_models.estimation import build_vessel_model
    from ship_models.hydro.panel import hull_mesh, write_gdf
    from ship_models.vessel import VesselData, VesselFileError, dump_vessel, load_vessel

    V, F = hull_mesh(seiner.hull, nx=50, nz=10)
    write_gdf(V, F, tmp_path / "hull.gdf")
    v = load_vessel("purse_seiner")
    for wf, ok in (("panel_fk", True), ("froude_krylov_strips", False)):
        meta = dict(v.meta) | {"hull_mesh": "hull.gdf", "wave_forces": wf}
        dump_vessel(VesselData("meshed", meta, dict(v.coefficients)), tmp_path / "m.toml")
        if not ok:
            with pytest.raises(VesselFileError, match="hull_mesh"):
                build_vessel_model(load_vessel(tmp_path / "m.toml"))
            continue
        from ship_models.hydro.panel import PanelWaveBuilder

        builder = PanelWaveBuilder(
            diffraction=False, lambda_over_L=(1.0, 1.5, 2.0, 2.5, 3.0), chi_deg=(0.0, 20.0, 40.0)
        )
        data = build_vessel_model(load_vessel(tmp_path / "m.toml"), waves=builder)
        assert wave_model_name(data) == "panel_fk"
        args = (0.3, 8.0, 0.2, SeaState(HL, LL))
        got = np.array(data.forces.waves.forces(*args, lift=False))
        ref = np.array(seiner.forces.waves.forces(*args, lift=False))
        assert abs(got[0] / ref[0] - 1) < 0.03  # 1,000 panels, 5 x 4 table fit
