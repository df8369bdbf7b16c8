"""The main job's sensitivity step: its files, its summary and the report's section.

The computation itself (adjoint derivatives against re-solved connections, the band
against samples) is tested in ``tests/test_sensitivity.py``; here the step's output
and the report are checked on a small hand-made result whose band is known in closed
form, so the test is fast.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from broachkit_cli.report import sensitivity_context, write_report
from ship_models.analysis.sensitivity import Sensitivity, SensitivityEntry, UncertaintyBand
from ship_models.paper import PAPER_FN_BRACKET
from studies import sensitivity as step
from studies._common import split_run_record

FN = 0.30


def _entry(key: str, value: float, d: float, status: str = "estimated",
           kind: str = "estimated") -> SensitivityEntry:  # fmt: skip
    return SensitivityEntry(key, value, "-", status, "test", d, value / FN * d, 1e-4,
                            "central", kind)  # fmt: skip


def _result(sigmas: dict[str, float]) -> tuple[Sensitivity, UncertaintyBand]:
    entries = (
        _entry("hydrodynamics.wave_surge_scale", 1.0, -0.07, "assumed", "file"),
        _entry("propulsion.w_P", 0.2, 0.026),
        _entry("hydrodynamics.m_x", 3.0e4, 1.3e-7),
        _entry("resistance.knot_spacing_Fn", 0.05, 0.1, "given", "numerical"),
    )
    mesh = SimpleNamespace(n_intervals=80)
    conn = SimpleNamespace(residual_norm=1e-12, orbit=SimpleNamespace(mesh=mesh))
    sens = Sensitivity(math.radians(10.0), FN, entries, conn)  # type: ignore[arg-type]
    by = {e.key: e for e in entries}
    contrib = sorted(((k, abs(by[k].dFn_dtheta) * s) for k, s in sigmas.items()),
                     key=lambda kv: -kv[1])  # fmt: skip
    sigma = math.sqrt(sum(v * v for _, v in contrib))
    return sens, UncertaintyBand(FN, sigma, tuple(contrib), np.zeros(0), np.zeros(0))


def test_step_writes_tornado_and_summary_with_the_band(tmp_path: Path) -> None:
    sigmas = {"hydrodynamics.wave_surge_scale": 0.1, "propulsion.w_P": 0.05,
              "hydrodynamics.m_x": 3.0e3}  # fmt: skip
    sens, band = _result(sigmas)
    s = step.write_outputs(tmp_path, sens, band, seconds=1.0)
    assert (tmp_path / "tornado.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    on_disk = json.loads((tmp_path / "summary.json").read_text())
    results, record = split_run_record(json.loads(json.dumps(s)))
    assert on_disk == results  # the results; this run's clock beside them
    assert json.loads((tmp_path / "timings.json").read_text()) == record == {"elapsed_s": 1.0}
    full = json.loads((tmp_path / "sensitivity.json").read_text())
    assert len(full["sensitivity"]["entries"]) == 4
    # closed form: sigma^2 = (0.07*0.1)^2 + (0.026*0.05)^2 + (1.3e-7*3e3)^2
    sig = math.sqrt((0.007) ** 2 + (0.0013) ** 2 + (3.9e-4) ** 2)
    assert s["sigma_linear"] == pytest.approx(sig, rel=1e-12)
    assert s["band"] == pytest.approx([FN - 1.96 * sig, FN + 1.96 * sig], rel=1e-12)
    assert [d["key"] for d in s["dominant"]] == [
        "hydrodynamics.wave_surge_scale",
        "propulsion.w_P",
        "hydrodynamics.m_x",
    ]
    assert sum(d["share"] for d in s["dominant"]) == pytest.approx(1.0, rel=1e-12)
    # 0.3247 > 0.30 + 1.96 * 0.0072: outside
    assert s["paper_inside_band"] is False
    assert s["paper_Fn"] == list(PAPER_FN_BRACKET)
    # the numerical fit setting is not in the elasticity list
    assert "resistance.knot_spacing_Fn" not in [e["key"] for e in s["elasticities"]]
    assert not list(tmp_path.glob(".*tmp*"))  # atomic writes leave no temporary


def test_paper_inside_a_wide_band(tmp_path: Path) -> None:
    sens, band = _result({"hydrodynamics.wave_surge_scale": 0.5})  # sigma 0.035
    s = step.write_outputs(tmp_path, sens, band, seconds=1.0)
    assert s["paper_inside_band"] is True


def test_report_section_reads_the_steps_summary(tmp_path: Path) -> None:
    sens, band = _result({"hydrodynamics.wave_surge_scale": 0.1, "propulsion.w_P": 0.05})
    s = step.write_outputs(tmp_path / "sensitivity", sens, band, seconds=1.0)
    s = json.loads((tmp_path / "sensitivity" / "summary.json").read_text())
    ctx = sensitivity_context({"sensitivity": s})
    assert ctx is not None
    rows = dict(ctx["rows"])
    lo, hi = s["band"]
    assert rows["band (Fn -+ 1.96 sigma)"] == f"[{lo:.8g}, {hi:.8g}]"
    assert rows["the paper's value inside the band"] == "no"
    assert [k for k, _, _ in ctx["dominant"]] == ["hydrodynamics.wave_surge_scale",
                                                  "propulsion.w_P"]  # fmt: skip
    html = write_report(tmp_path, {"sensitivity": s}, {}).read_text()
    assert f"[{lo:.8g}, {hi:.8g}]" in html
    assert 'src="sensitivity/tornado.png"' in html
    assert (tmp_path / "sensitivity" / "tornado.png").is_file()
    assert sensitivity_context({}) is None
    empty = write_report(tmp_path, {}, {}).read_text()
    assert "Not run (the <code>sensitivity</code> step" in empty


def test_step_is_in_the_main_job() -> None:
    from broachkit_cli.commands.reproduce import STUDY_STEPS

    assert ("sensitivity", "sensitivity") == next(
        (k, m) for k, _, m in STUDY_STEPS if k == "sensitivity"
    )


def test_main_job_keys_cover_every_uncertainty() -> None:
    from ship_models.analysis.sensitivity import FACTORS
    from ship_models.estimation import build_vessel_model
    from ship_models.vessel import load_vessel

    v = load_vessel("purse_seiner")
    keys = step.main_job_keys(v)
    resolved = build_vessel_model(v).vessel
    assert {k for k in resolved.uncertainties if k in resolved.coefficients} <= set(keys)
    assert set(FACTORS) <= set(keys)
    assert len(keys) == len(set(keys))


def test_reused_hydrostatics_give_the_fresh_build_and_follow_changed_inputs() -> None:
    from ship_models.analysis.sensitivity import reuse_hydrostatics
    from ship_models.estimation import build_vessel_model
    from ship_models.vessel import Coefficient, load_vessel

    v = load_vessel("purse_seiner")
    B = v.coefficients["particulars.B"]
    wider = v.with_overrides({"particulars.B": Coefficient(B.value * 1.01, B.unit, B.source,
                                                           B.status)})  # fmt: skip
    fresh = [build_vessel_model(x).vessel.coefficients for x in (v, wider)]
    with reuse_hydrostatics() as stats:
        build_vessel_model(v)
        cached = [build_vessel_model(x).vessel.coefficients for x in (v, wider)]
    assert stats["hits"] >= 3  # gz_curve, topside fit and resistance fit of the second v
    for a, b in zip(fresh, cached, strict=True):
        assert {k: c.value for k, c in a.items()} == {k: c.value for k, c in b.items()}
    # the wider hull changed the hydrostatics: its topside height is not the base one
    top = "stability.topside_height"
    assert cached[1][top].value != cached[0][top].value
