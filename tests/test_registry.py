"""Model registry: packaged vessels, files by path, registered factories, entry-point plugins."""

from __future__ import annotations

import logging
import shutil
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from continuation import System, continue_equilibria
from continuation.newton import newton
from continuation.settings import NewtonSettings
from ship_models import (
    Coefficient,
    PluginError,
    SurgeModel,
    Umeda4DOF,
    VesselFileError,
    get_model,
    get_vessel_data,
    list_models,
    load_model_file,
    model_info,
    register_model,
)
from ship_models import registry as reg
from ship_models.vessel import DATA_DIR, available_vessels


def test_packaged_vessels_are_registered_with_surge_variants():
    names = list_models()
    for stem in available_vessels():
        assert stem in names and f"{stem}_surge" in names
    assert {"purse_seiner", "purse_seiner_surge", "kvlcc2", "kvlcc2_surge"} <= set(names)
    info = model_info("purse_seiner")
    assert info.kind == "4dof" and info.origin == "built-in"
    assert "purse seiner" in info.description.lower()
    assert model_info("kvlcc2_surge").kind == "surge"


def test_get_model_builds_the_vessels_model():
    m = get_model("purse_seiner")
    assert isinstance(m, Umeda4DOF)
    assert m.vessel.name == "purse_seiner"
    assert m.vessel.get("particulars.L_pp") == 34.5  # Umeda (1999) Table 1
    s = get_model("purse_seiner_surge")
    assert isinstance(s, SurgeModel) and s.state_names == ("xi_G", "u")
    # the surge model of the registry is the chi_c = 0 reduction of the 4-DOF model
    x = np.array([0.3, 8.0, 0, 0, 0, 0, 0, 0.0])
    p4 = m.default_params().replace(chi_c=0.0)
    np.testing.assert_allclose(
        s.f(x[:2], s.default_params().values), m.f(x, p4.values)[:2], rtol=1e-12
    )


def test_options_reach_the_model():
    lin = get_model("purse_seiner", saturation=False)
    sat = get_model("purse_seiner")
    p = sat.default_params().values
    x = np.zeros(8)
    x[1] = 6.0
    x[3] = p[1] - 3.0  # heading error far beyond the rudder limit
    F = sat.forces
    # saturated command tends to delta_max; linear command is K_R * 3 rad
    assert sat.f(x, p)[7] * F.T_E == pytest.approx(F.delta_max, rel=1e-6)
    assert lin.f(x, p)[7] * F.T_E == pytest.approx(3.0 * p[4], rel=1e-12)


def test_overrides_option():
    m = get_model("purse_seiner", overrides={"loading.GM": 1.1})
    assert m.vessel.get("loading.GM") == 1.1
    c = m.vessel.coefficient("loading.GM")
    assert c.status == "measured" and c.source == "user override"
    # GZ'(0) = GM is imposed on the fit: the override reaches the force model
    assert m.data.gz.slope0() == pytest.approx(1.1, rel=1e-12)
    coef = Coefficient(-0.5, "-", "PMM test, report X", "measured")
    m2 = get_model("purse_seiner_surge", overrides={"hydrodynamics.Y_v_prime": coef})
    assert m2.vessel.coefficient("hydrodynamics.Y_v_prime") == coef
    with pytest.raises(VesselFileError, match=r"loading\.GMX"):
        get_model("purse_seiner", overrides={"loading.GMX": 1.0})
    with pytest.raises(ValueError, match="overrides"):
        get_model("purse_seiner", overrides=[("loading.GM", 1.0)])


def test_unknown_name_and_option_are_value_errors():
    with pytest.raises(ValueError, match="unknown model 'no_such_ship'.*purse_seiner"):
        get_model("no_such_ship")
    with pytest.raises(ValueError, match=r"unknown option\(s\) \['colour'\].*saturation"):
        get_model("purse_seiner", colour="red")
    with pytest.raises(ValueError, match="unknown option"):
        get_model("purse_seiner_surge", saturation=False)


def test_model_from_file_path(tmp_path: Path):
    f = tmp_path / "copy_of_seiner.toml"
    f.write_text((DATA_DIR / "purse_seiner.toml").read_text().replace('"purse_seiner"', '"copy"'))
    ref = get_model("purse_seiner")
    for m in (get_model(str(f)), get_model(f), load_model_file(f)):
        assert isinstance(m, Umeda4DOF) and m.vessel.name == "copy"
        x = ref.random_state(4)
        p = ref.default_params().values
        np.testing.assert_allclose(m.f(x, p), ref.f(x, p), rtol=1e-12)
    s = load_model_file(f, kind="surge")
    assert isinstance(s, SurgeModel)
    with pytest.raises(ValueError, match="kind"):
        load_model_file(f, kind="6dof")
    with pytest.raises(ValueError, match="no vessel file"):
        get_model(str(tmp_path / "missing.toml"))
    bad = tmp_path / "bad.toml"
    bad.write_text(f.read_text().replace('value = 1.0, unit = "m"', 'value = -1.0, unit = "m"'))
    with pytest.raises(VesselFileError, match=r"loading\.GM"):
        get_model(str(bad))


def test_register_model_decorator_and_call():
    def toy_rhs(x, p, ops):
        return ops.stack([p[0] - x[0] ** 2])

    try:

        @register_model("toy_fold", description="fold normal form")
        def toy(*, mu0: float = 1.0) -> System:
            return System(toy_rhs, ("x",), ("mu",), defaults={"mu": mu0})

        assert toy.__name__ == "toy"  # the decorator returns the factory unchanged
        assert "toy_fold" in list_models()
        m = get_model("toy_fold", mu0=2.0)
        assert m.params()["mu"] == 2.0
        info = model_info("toy_fold")
        assert info.origin == "registered" and info.description == "fold normal form"
        with pytest.raises(ValueError, match="already registered"):
            register_model("toy_fold", toy)
        with pytest.raises(ValueError, match="already registered"):
            register_model("purse_seiner", toy)
        register_model("toy_fold", lambda: System(toy_rhs, ("x",), ("mu",)), replace=True)
        with pytest.raises(ValueError, match="unknown option"):
            get_model("toy_fold", mu0=2.0)
        with pytest.raises(ValueError, match="no vessel data"):
            get_vessel_data("toy_fold")
        register_model("not_a_system", lambda: 42)
        with pytest.raises(ValueError, match="not a dynamical system"):
            get_model("not_a_system")
    finally:
        for n in ("toy_fold", "not_a_system"):
            if n in list_models():
                reg.unregister_model(n)
    for bad in ("", "9lives", "a b", "x.toml", None):
        with pytest.raises(ValueError, match="name"):
            register_model(bad, lambda: None)
    with pytest.raises(ValueError, match="callable"):
        register_model("not_callable", 3)
    with pytest.raises(ValueError, match="not registered"):
        reg.unregister_model("never_registered")


def test_get_vessel_data_without_building_the_model(tmp_path: Path):
    d = get_vessel_data("kvlcc2")
    assert d.vessel.name == "kvlcc2" and d.forces.L == 320.0
    d2 = get_vessel_data("purse_seiner", overrides={"loading.GM": 1.2})
    assert d2.forces.gz_coeffs @ np.arange(1, d2.forces.gz_coeffs.size + 1) == pytest.approx(1.2)
    f = tmp_path / "k.toml"
    shutil.copy(DATA_DIR / "kvlcc2.toml", f)
    assert get_vessel_data(str(f)).vessel.get("loading.GM") == 5.71
    with pytest.raises(ValueError, match="no vessel file"):
        get_vessel_data(str(tmp_path / "none.toml"))


# ---------------------------------------------------------------------- plugins
PLUGIN_MODULE = "bk_test_vessel_plugin"


def _write_distribution(root: Path) -> None:
    """A real installed distribution: package + ``*.dist-info`` with entry points."""
    pkg = root / PLUGIN_MODULE
    pkg.mkdir()
    toml = (DATA_DIR / "purse_seiner.toml").read_text().replace('"purse_seiner"', '"ferry"')
    toml = toml.replace(
        'GM = { value = 1.0, unit = "m", source = "Umeda (1999) Table 1", status = "given" }',
        'GM = { value = 1.15, unit = "m", source = "inclining test", status = "measured" }',
    )
    (pkg / "ferry.toml").write_text(toml)
    (pkg / "__init__.py").write_text(
        textwrap.dedent(
            """
            from pathlib import Path

            from ship_models import Umeda4DOF, load_vessel

            TOML_PATH = str(Path(__file__).with_name("ferry.toml"))
            VESSEL = load_vessel(TOML_PATH)
            NUMBER = 42


            def make_ferry(*, wave_lift=True):
                \"\"\"Test ferry, 4-DOF model.\"\"\"
                return Umeda4DOF(VESSEL, wave_lift=wave_lift)


            def make_nothing():
                return "not a model"
            """
        )
    )
    info = root / f"{PLUGIN_MODULE}-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {PLUGIN_MODULE}\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(
        textwrap.dedent(
            f"""
            [broachkit.models]
            test_ferry = {PLUGIN_MODULE}:make_ferry
            test_ferry_data = {PLUGIN_MODULE}:VESSEL
            test_ferry_file = {PLUGIN_MODULE}:TOML_PATH
            test_broken = bk_no_such_module_xyz:make
            test_number = {PLUGIN_MODULE}:NUMBER
            test_nothing = {PLUGIN_MODULE}:make_nothing
            purse_seiner = {PLUGIN_MODULE}:make_ferry

            [some.other.group]
            ignored = {PLUGIN_MODULE}:make_ferry
            """
        )
    )


@pytest.fixture()
def plugin_dist(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    root = tmp_path / "site"
    root.mkdir()
    _write_distribution(root)
    monkeypatch.syspath_prepend(str(root))
    reg.refresh_plugins()
    yield root
    monkeypatch.undo()
    sys.modules.pop(PLUGIN_MODULE, None)
    reg.refresh_plugins()


def test_entry_point_plugins_found_lazily(plugin_dist, caplog):
    names = list_models()
    for n in ("test_ferry", "test_ferry_data", "test_ferry_file", "test_broken"):
        assert n in names
    assert "ignored" not in names  # other entry-point groups are not ours
    assert PLUGIN_MODULE not in sys.modules  # discovered, not imported
    info = model_info("test_ferry")
    assert info.origin == "entry point" and f"{PLUGIN_MODULE}:make_ferry" in info.target
    assert f"{PLUGIN_MODULE} 0.1" in info.target  # names the distribution

    m = get_model("test_ferry", wave_lift=False)
    assert PLUGIN_MODULE in sys.modules
    assert isinstance(m, Umeda4DOF) and not m.wave_lift
    assert m.vessel.name == "ferry" and m.vessel.get("loading.GM") == 1.15
    assert model_info("test_ferry").description == "Test ferry, 4-DOF model."
    with pytest.raises(ValueError, match="unknown option"):
        get_model("test_ferry", saturation=False)

    # a VesselData and a path to a file are wrapped into the 4-DOF model
    for n in ("test_ferry_data", "test_ferry_file"):
        mm = get_model(n)
        assert isinstance(mm, Umeda4DOF) and mm.vessel.get("loading.GM") == 1.15
        assert get_vessel_data(n).vessel.coefficient("loading.GM").status == "measured"
    x = m.random_state(1)
    p = m.default_params().values
    np.testing.assert_allclose(
        get_model("test_ferry_data", wave_lift=False).f(x, p), m.f(x, p), rtol=1e-12
    )


def test_broken_plugin_is_named_and_does_not_break_others(plugin_dist):
    with pytest.raises(PluginError) as err:
        get_model("test_broken")
    msg = str(err.value)
    assert "test_broken = bk_no_such_module_xyz:make" in msg
    assert "broachkit.models" in msg and PLUGIN_MODULE in msg  # group and distribution
    assert "ModuleNotFoundError" in msg
    with pytest.raises(PluginError, match="test_number.*int.*expected a model factory"):
        get_model("test_number")
    with pytest.raises(PluginError, match="test_nothing.*not a dynamical system"):
        get_model("test_nothing")
    # the others still work, before and after the failures
    assert isinstance(get_model("test_ferry"), Umeda4DOF)
    assert isinstance(get_model("purse_seiner"), Umeda4DOF)
    assert "test_broken" in list_models()


def test_plugin_cannot_shadow_a_builtin(plugin_dist, caplog):
    with caplog.at_level(logging.WARNING, logger="ship_models.registry"):
        reg.refresh_plugins()
    assert model_info("purse_seiner").origin == "built-in"
    assert get_model("purse_seiner").vessel.get("loading.GM") == 1.0
    assert any("already registered" in r.getMessage() for r in caplog.records)


# ---------------------------------------------------------------------- engine
def test_crest_equilibrium_continues_in_chi_c_through_the_engine():
    """`continue_equilibria(get_model("purse_seiner"), ...)`: the surf-riding equilibrium
    near the crest (Umeda 1999, Figs. 2-5) continued from chi_c = 0 to 6 deg.

    Every branch point solves f = 0, and agrees with an independent Newton solve of
    the same equation started from the analytic guess of ``equilibrium_guess``.
    """
    m = get_model("purse_seiner")
    p = m.default_params().replace(chi_c=0.0)
    x0 = m.equilibrium_guess(p, where="crest")
    br = continue_equilibria(
        m, x0, p, "chi_c", ds=0.01, ds_max=0.03, p_min=0.0, p_max=np.deg2rad(6.0),
        direction="forward", max_steps=30,
    )  # fmt: skip
    assert br.status.ok, br.status
    assert len(br) >= 4
    assert br.p[-1] == pytest.approx(np.deg2rad(6.0), abs=1e-12)
    assert np.all(np.diff(br.p) > 0)
    s = NewtonSettings(tol=1e-11, max_iter=50, damping=True)
    for k in range(len(br)):
        pk = p.replace(chi_c=br.p[k]).values
        assert np.max(np.abs(m.f(br.x[k], pk))) < 1e-8
        ref = newton(
            lambda z, pk=pk: m.f(z, pk),
            lambda z, pk=pk: m.jacobian(z, pk),
            m.equilibrium_guess(pk, "crest"),
            s,
        )
        assert ref.converged
        np.testing.assert_allclose(m.difference(br.x[k], ref.z), 0.0, atol=1e-7)
    # along the branch the crest equilibrium stays an index-1 saddle (Umeda 1999, Fig. 6)
    assert np.all(br.n_unstable == 1)
    # chi follows the course: chi > 0 for chi_c > 0 (and chi = 0 at chi_c = 0 by symmetry)
    chi = br.state("chi")
    assert abs(chi[0]) < 1e-10 and np.all(chi[1:] > 0)
