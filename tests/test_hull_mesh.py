"""A closed mesh as the hull: hydrostatics and GZ against closed forms (box: exact; circular
cylinder: second order in the facet size), the same hull as a mesh and as offsets meet
(hydrostatics, GZ, strip forces), bad meshes refused in one line, the CLI on a mesh vessel."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from ship_models import get_vessel_data
from ship_models.contracts import SeaState
from ship_models.estimation import form_parameters
from ship_models.hydro.hydrostatics import gz_curve
from ship_models.hydro.mesh import check_wetted_mesh, mesh_volume
from ship_models.hydro.mesh_hull import (
    MeshHull,
    box_mesh,
    horizontal_cylinder_mesh,
    hull_from_mesh,
    offsets_closed_mesh,
    wetted_panels,
)
from ship_models.hydro.mesh_hydrostatics import mesh_gz_curve, mesh_hydrostatics
from ship_models.hydro.mesh_io import (
    MeshError,
    clean_closed_mesh,
    read_mesh_file,
    write_obj,
    write_stl,
)
from ship_models.hydro.offsets import (
    OffsetsError,
    form_parameter_offsets,
    hull_from_offsets,
    read_offsets,
    wigley_offsets,
)
from ship_models.hydro.upright import hydrostatics
from ship_models.hydro.waves import WaveStrips

#: The purse seiner's wave (H/lambda = 1/9.2, lambda/L = 1.5) for the force checks.
SEA = SeaState(1 / 9.2, 1.5)

EXAMPLES = Path(__file__).resolve().parents[1] / "docs" / "examples"
L, B, T, D = 34.5, 7.0, 2.6, 3.6  # the Wigley example


# ------------------------------------------------------------------ closed forms
@pytest.mark.parametrize("n", [1, 4])
def test_box_hydrostatics_and_wall_sided_gz_are_exact_at_any_resolution(n):
    """A box's faces are flat, so the integration is exact at every resolution (rounding
    only): V = LBT, KB = T/2, BM = B^2/(12T), I_L = BL^3/12, and while the deck edge stays
    dry and the bilge wet (tan(phi) <= 2 min(T, D - T)/B) the wall-sided formula
    GZ = (GM + BM tan^2(phi)/2) sin(phi) is exact too (free trim stays 0)."""
    Lb, Bb, Db, Tb = 20.0, 6.0, 4.0, 1.8
    V, Tr = box_mesh(Lb, Bb, Db, Tb, n)
    hs = mesh_hydrostatics(V, Tr)
    exact = {"volume": Lb * Bb * Tb, "KB": Tb / 2, "BM": Bb**2 / (12 * Tb), "A_wp": Lb * Bb,
             "I_T": Lb * Bb**3 / 12, "I_L": Bb * Lb**3 / 12, "C_b": 1.0}  # fmt: skip
    for k, v in exact.items():
        assert getattr(hs, k) == pytest.approx(v, rel=1e-12), k
    assert abs(hs.lcb) < 1e-12 * Lb and abs(hs.lcf) < 1e-12 * Lb
    # a face lying in the waterplane (deck awash) is the waterplane, not wetted hull
    awash = mesh_hydrostatics(*box_mesh(Lb, Bb, Db, Db, n))
    assert awash.A_wp == pytest.approx(Lb * Bb, rel=1e-12)
    assert awash.volume == pytest.approx(Lb * Bb * Db, rel=1e-12)
    GM = 0.6
    phi_lim = math.atan(2 * min(Tb, Db - Tb) / Bb)  # 31 deg
    gz = mesh_gz_curve(V, Tr, GM, heel_step=math.radians(2.0), phi_max=math.radians(60.0))
    wall = (GM + 0.5 * hs.BM * np.tan(gz.phi) ** 2) * np.sin(gz.phi)
    inside = gz.phi <= phi_lim
    np.testing.assert_allclose(gz.gz[inside], wall[inside], rtol=0, atol=1e-12 * Bb)
    assert np.max(np.abs(gz.gz[~inside] - wall[~inside])) > 1e-3  # the formula's limit is real


def _cylinder_errors(n):
    """Errors of a half-immersed horizontal circular cylinder (axis on the waterline)."""
    Lc, R, KG = 10.0, 1.5, 1.2  # G 0.3 m below the axis: GM = KM - KG = R - KG
    V, Tr = horizontal_cylinder_mesh(Lc, R, 0.0, n)
    hs = mesh_hydrostatics(V, Tr)
    zc = 4 * R / (3 * math.pi)  # centroid of the half disc below the axis
    exact = {"volume": math.pi * R * R * Lc / 2, "KB": R - zc, "BM": zc}
    err = np.array([abs(getattr(hs, k) / v - 1) for k, v in exact.items()])
    GM = R - KG
    gz = mesh_gz_curve(V, Tr, GM, heel_step=math.radians(5.0), phi_max=math.pi)
    # a circle: the buoyancy always acts through the axis, GZ = GM sin(phi) at every heel
    err_gz = np.max(np.abs(gz.gz - GM * np.sin(gz.phi))) / R
    return err, err_gz


def test_circular_cylinder_converges_at_second_order():
    """An inscribed n-gon errs by O((2 pi/n)^2) (its area by (2 pi/n)^2/6): doubling n
    quarters every error, and each is within that bound."""
    e1, g1 = _cylinder_errors(32)
    e2, g2 = _cylinder_errors(64)
    h2 = (2 * math.pi / 32) ** 2
    assert np.all(e1 < h2) and g1 < h2
    np.testing.assert_allclose(e1 / e2, 4.0, rtol=0.05)
    assert 3.0 < g1 / g2 < 5.0


# ------------------------------------------------------------------ both paths meet
def test_wigley_as_a_mesh_has_the_hydrostatics_and_gz_of_its_offsets():
    """The mesh of the offsets' bilinear surface differs from it only by the split of each
    twisted cell into two flat triangles: O(h^2), measured by refining (errors quarter).
    Volume, KB, BM and the waterplane are linear along the grid lines, hence equal."""
    tab = wigley_offsets(L=L, B=B, T=T, D=D)
    oh = hull_from_offsets(tab, L=L, D=D, d_f=T, d_a=T)
    ref = hydrostatics(oh)
    g_ref = gz_curve(oh, 0.8, heel_step=math.radians(2.0))
    d_lcb = []
    for r in (1, 2):
        V, Tr = offsets_closed_mesh(tab, L=L, D=D, d_f=T, d_a=T, refine=r)
        hs = mesh_hydrostatics(V, Tr, L=L, B=oh.B, d_m=T)
        for k in ("volume", "KB", "BM", "A_wp", "I_T", "I_L", "C_b"):
            assert getattr(hs, k) == pytest.approx(getattr(ref, k), rel=1e-9), k
        d_lcb.append(abs(hs.lcb - ref.lcb))
        g = mesh_gz_curve(V, Tr, 0.8, heel_step=math.radians(2.0))
        assert g.zeta_G == pytest.approx(g_ref.zeta_G, abs=1e-9)
        # the strip GZ has its own x-quadrature error at heel (2 Gauss nodes per station
        # interval): 0.2 mm here; 1 mm = 0.4 % of GZ_max
        np.testing.assert_allclose(g.gz, g_ref.gz, atol=1e-3)
    assert d_lcb[0] < 1e-3 * L and d_lcb[0] / d_lcb[1] > 3.5


@pytest.fixture(scope="module")
def seiner():
    return get_vessel_data("purse_seiner")


def test_form_parameter_hull_as_a_mesh_gives_the_strip_forces_of_the_offsets(seiner):
    """The purse seiner's form-parameter hull (trimmed 0.3 m by the stern) as offsets and
    as a closed mesh: the mesh's strips are sliced from it at 81 stations, so they carry
    the slicing's interpolation error on top of the triangles': forces within 0.3 %,
    hydrostatics within 0.1 %, GZ within 1 mm."""
    fp = form_parameters(seiner.vessel)
    tab = form_parameter_offsets(fp, n_stations=81, n_waterlines=41)
    oh = hull_from_offsets(tab, L=fp.L, D=fp.D, d_f=fp.d_f, d_a=fp.d_a)
    V, Tr = offsets_closed_mesh(tab, L=fp.L, D=fp.D, d_f=fp.d_f, d_a=fp.d_a)
    mh = hull_from_mesh((V, Tr), L=fp.L, D=fp.D, d_f=fp.d_f, d_a=fp.d_a,
                        B=fp.B, C_b=fp.C_b, lcb_aft=-fp.lcb)  # fmt: skip
    a, b = hydrostatics(oh), hydrostatics(mh)
    for k in ("volume", "A_wp", "I_T", "BM", "KB"):
        assert getattr(b, k) == pytest.approx(getattr(a, k), rel=1e-3), k
    # the mesh's x runs along the trimmed waterline, the table's along the baseline:
    # the LCBs differ by KB sin(trim) (10 mm here) plus the triangles' O(h^2)
    trim = (fp.d_a - fp.d_f) / fp.L
    assert abs(b.lcb - a.lcb) < 1.5 * a.KB * trim
    assert mh.volume == pytest.approx(b.volume, rel=1e-3)  # strips vs exact mesh
    # GZ at heel with free sinkage and trim: the mesh's own (clipped at the inclined
    # waterplane) against the offsets' strip sections, within 1 mm (0.6 % of GZ_max)
    ga = gz_curve(oh, 1.0, heel_step=math.radians(3.0))
    gb = gz_curve(mh, 1.0, heel_step=math.radians(3.0))
    np.testing.assert_allclose(gb.gz, ga.gz, atol=1e-3)
    w0 = seiner.forces.waves
    xi = np.linspace(0.0, 1.0, 16, endpoint=False)
    out = []
    for hull in (oh, mh):
        w = WaveStrips.from_hull(hull, x_G=seiner.info["x_G"], zeta_G=seiner.info["zeta_G"],
                                 m22=np.interp(hull.x, seiner.hull.x, w0.m22), z_H=w0.z_H,
                                 rho=w0.rho, g=w0.g, n_depth=8)  # fmt: skip
        out.append(np.array([w.forces(s, 8.0, 0.3, SEA, lift=False) for s in xi]))
    err = np.max(np.abs(out[1] - out[0]), axis=0) / np.max(np.abs(out[0]), axis=0)
    assert np.all(err < 3e-3), err


def test_heeled_equilibrium_keeps_the_displacement_with_free_or_fixed_trim(seiner):
    """At heel the level (and, optionally, the trim) is solved so that the volume (and
    the LCB) stay the upright ones; on the fore-aft asymmetric seiner hull the free trim
    is not zero and moves GZ."""
    from ship_models.hydro.mesh_hydrostatics import clipped_integrals, mesh_heeled_equilibrium

    fp = form_parameters(seiner.vessel)
    tab = form_parameter_offsets(fp, n_stations=41, n_waterlines=21)
    V, Tr = offsets_closed_mesh(tab, L=fp.L, D=fp.D, d_f=fp.d_f, d_a=fp.d_a)
    up = clipped_integrals(V, Tr, 0.0, 0.0)
    phi = math.radians(40.0)
    free = mesh_heeled_equilibrium(V, Tr, phi, up.volume, up.centre[0])
    fixed = mesh_heeled_equilibrium(V, Tr, phi, up.volume, up.centre[0], free_trim=False)
    assert free.converged and fixed.converged and fixed.theta == 0.0
    for st in (free, fixed):
        assert st.volume == pytest.approx(up.volume, rel=1e-10)
    assert free.x_B == pytest.approx(up.centre[0], abs=1e-9 * fp.L)
    assert abs(free.theta) > 1e-4 and abs(fixed.x_B - up.centre[0]) > 1e-3
    assert abs(free.y_B - fixed.y_B) + abs(free.zeta_B - fixed.zeta_B) > 1e-4


# ------------------------------------------------------------------ files
def test_mesh_files_round_trip_in_every_format(tmp_path):
    V, Tr = offsets_closed_mesh(wigley_offsets(L=L, B=B, T=T, D=D), L=L, D=D, d_f=T, d_a=T)
    ref = mesh_hydrostatics(V, Tr)
    paths = [write_obj(V, Tr, tmp_path / "h.obj"), write_stl(V, Tr, tmp_path / "h.stl")]
    meshio = pytest.importorskip("meshio")
    for ext in ("vtk", "ply"):
        p = tmp_path / f"h.{ext}"
        meshio.write(p, meshio.Mesh(V, [("triangle", Tr)]))
        paths.append(p)
    for p in paths:
        got = mesh_hydrostatics(*clean_closed_mesh(*read_mesh_file(p), source=str(p)))
        tol = 1e-6 if p.suffix == ".stl" else 1e-7  # STL stores float32, OBJ 6 decimals
        assert got.volume == pytest.approx(ref.volume, rel=tol), p.suffix
        assert got.BM == pytest.approx(ref.BM, rel=10 * tol), p.suffix


def test_the_shipped_example_mesh_is_the_example_offsets_as_a_mesh():
    """docs/examples/wigley_hull.obj is what its header says: regenerated here."""
    V0, T0 = clean_closed_mesh(*read_mesh_file(EXAMPLES / "wigley_hull.obj"))
    V, Tr = offsets_closed_mesh(read_offsets(EXAMPLES / "wigley_offsets.csv"), L=L, D=D,
                                d_f=T, d_a=T)  # fmt: skip
    assert T0.shape == Tr.shape
    np.testing.assert_allclose(V0[T0], V[Tr], atol=1e-6)
    text = (EXAMPLES / "wigley_hull.obj").read_text()
    assert "offsets_closed_mesh" in text and "wigley_offsets.csv" in text


def test_wetted_panels_of_a_mesh_hull_are_closed_and_displace_it():
    mh = hull_from_mesh(EXAMPLES / "wigley_hull.obj", L=L, D=D)
    Vw, F = wetted_panels(mh)
    check_wetted_mesh(Vw, F)
    assert np.all(Vw[:, 2] <= 1e-12)
    assert mesh_volume(Vw, np.c_[F, F[:, 2]]) == pytest.approx(hydrostatics(mh).volume, rel=2e-2)


def test_panel_froude_krylov_on_the_mesh_equals_its_strips():
    """Capytaine's Froude-Krylov force on the mesh clipped at the waterline = the strips
    sliced from the same mesh (no BEM solve): within 1 % (roll 2 %) on 1,600 panels and
    second order (errors quarter) on refining."""
    pytest.importorskip("capytaine")
    from ship_models.hydro.panel import hull_mesh, panel_table

    tab0 = wigley_offsets(L=L, B=B, T=T, D=D, n_stations=41, n_waterlines=11)
    a = 0.5 / 9.2 * 1.5 * L
    xi = np.linspace(0.0, 1.0, 64, endpoint=False)
    errs = []
    for r in (1, 2):
        mh = hull_from_mesh(offsets_closed_mesh(tab0, L=L, D=D, d_f=T, d_a=T, refine=r), L=L, D=D)
        Vw, F = hull_mesh(mh)
        st = WaveStrips.from_hull(mh, x_G=0.0, zeta_G=-0.16, m22=np.zeros(mh.n_stations),
                                  z_H=-1.3, rho=1025.0, g=9.80665, n_depth=8)  # fmt: skip
        tab = panel_table(Vw, F, L=L, x_G=0.0, zeta_G=-0.16, rho=1025.0, g=9.80665,
                          lambda_over_L=[1.5], chi_deg=[30.0], solve=False,
                          cache=False)  # fmt: skip
        ref = np.array([st.forces(s, 8.0, math.radians(30.0), SEA, lift=False)
                        for s in xi])  # fmt: skip
        got = np.array([[-a * np.real(tab.fk[n, 0, 0] * np.exp(2j * np.pi * s))
                         for n in range(4)] for s in xi])  # fmt: skip
        errs.append(np.abs(got - ref).max(axis=0) / np.abs(ref).max(axis=0))
    assert np.all(errs[0] < [0.01, 0.01, 0.01, 0.02]), errs[0]
    assert np.all(errs[0] / errs[1] > 3.0), errs


# ------------------------------------------------------------------ bad input
def _one_line(exc_info):
    msg = str(exc_info.value)
    assert "\n" not in msg and "np.float64" not in msg and "Error" not in msg
    return msg


def _bad(V, Tr, **kw):
    with pytest.raises(OffsetsError) as e:  # MeshError is one
        hull_from_mesh((V, Tr), L=L, D=D, **kw)
    return _one_line(e)


def test_bad_meshes_are_refused_in_one_line(tmp_path):
    V, Tr = offsets_closed_mesh(wigley_offsets(L=L, B=B, T=T, D=D), L=L, D=D, d_f=T, d_a=T)
    assert "is open" in _bad(V, Tr[1:])
    assert "inverted" in _bad(V, Tr[:, ::-1])
    flipped = Tr.copy()
    flipped[5] = flipped[5, ::-1]
    assert "inconsistent normals" in _bad(V, flipped)
    assert "not a surface" in _bad(V, np.concatenate([Tr, Tr[:1]]))
    flat = V * [1.0, 0.0, 0.0]  # every face of zero area
    assert "degenerate" in _bad(flat, Tr)
    assert "degenerate" in _bad(V, Tr[:3])
    nan = V.copy()
    nan[0, 0] = np.nan
    assert "finite" in _bad(nan, Tr)
    assert "units inconsistent" in _bad(V * 1000.0, Tr)
    assert "does not cross the calm waterline" in _bad(V + [0.0, 0.0, 5.0], Tr)
    assert "not symmetric" in _bad(V + [0.0, 0.4, 0.0], Tr)
    ok = dict(d_f=T, d_a=T, B=B, C_b=4 / 9, lcb_aft=0.0)
    assert "`particulars.d_a`" in _bad(V, Tr, **(ok | {"d_f": 2.0, "d_a": 2.0}))
    assert "`particulars.C_b`" in _bad(V, Tr, **(ok | {"C_b": 0.5}))
    assert "`particulars.lcb_aft`" in _bad(V, Tr, **(ok | {"lcb_aft": 1.0}))
    assert "`particulars.B`" in _bad(V, Tr, **(ok | {"B": 7.5}))
    (tmp_path / "x.obj").write_text("v 0 0 0\nf 1 2\n")
    with pytest.raises(MeshError) as e:
        read_mesh_file(tmp_path / "x.obj")
    assert "line 2" in _one_line(e)
    with pytest.raises(MeshError) as e:
        read_mesh_file(tmp_path / "none.stl")
    assert "no mesh file" in _one_line(e)


# ------------------------------------------------------------------ the vessel and the CLI
@pytest.fixture
def mesh_vessel(tmp_path, monkeypatch):
    for name in ("wigley_hull.obj", "wigley_mesh_vessel.toml"):
        shutil.copy(EXAMPLES / name, tmp_path / name)
    monkeypatch.chdir(tmp_path)
    return tmp_path / "wigley_mesh_vessel.toml"


def test_vessel_defined_by_a_mesh_through_the_cli(mesh_vessel, capsys):
    from broachkit_cli.main import main

    assert main(["vessels", "validate", str(mesh_vessel)]) == 0
    assert "valid" in capsys.readouterr().out
    data = get_vessel_data(str(mesh_vessel))
    assert isinstance(data.hull, MeshHull)
    off = get_vessel_data(str(EXAMPLES / "wigley_vessel.toml"))
    assert data.hull.volume == pytest.approx(off.hull.volume, rel=1e-6)
    np.testing.assert_allclose(data.gz.gz, off.gz.gz, atol=1e-3)
    assert main(["vessels", "hydrostatics", str(mesh_vessel), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert "closed mesh" in doc["hull"]
    assert doc["hydrostatics"]["volume"] == pytest.approx(277.6730775, rel=1e-9)
    assert main(["fixed-points", "--vessel", str(mesh_vessel), "--fn", "0.3", "--chi-c", "10",
                 "--json"]) == 0  # fmt: skip
    assert json.loads(capsys.readouterr().out)


def test_a_vessel_file_whose_mesh_is_bad_is_refused_by_validate(mesh_vessel, capsys):
    from broachkit_cli.main import main

    V, Tr = clean_closed_mesh(*read_mesh_file(mesh_vessel.with_name("wigley_hull.obj")))
    write_obj(V, Tr[:, ::-1], mesh_vessel.with_name("wigley_hull.obj"))
    assert main(["vessels", "validate", str(mesh_vessel)]) == 1
    err = capsys.readouterr().err
    assert "`vessel.hull_mesh`" in err and "inverted" in err and len(err.strip().splitlines()) == 1


@pytest.mark.slow
def test_critical_fn_of_the_mesh_vessel_equals_the_offsets_vessel(mesh_vessel, capsys):
    """Same hull by two paths: the critical Fn at 10 deg agrees to the hull's O(h^2)
    discretisation difference (measured 1e-7)."""
    from broachkit_cli.main import main

    fn = []
    for p in (mesh_vessel, EXAMPLES / "wigley_vessel.toml"):
        assert main(["critical", "--vessel", str(p), "--chi-c", "10", "--method", "bvp",
                     "--json"]) == 0  # fmt: skip
        doc = json.loads(capsys.readouterr().out)
        assert doc["wave_force_model"] == "froude_krylov_strips"
        fn.append(doc["Fn"])
    assert fn[0] == pytest.approx(fn[1], abs=1e-4)
