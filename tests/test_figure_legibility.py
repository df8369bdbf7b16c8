"""Figures are legible at the report's width (issue 28: composite figures had ~5 px labels).

A PNG written by ``studies._common.save_figure`` or the tornado records its smallest
font size; its height on screen follows from the PNG's pixel width and DPI and the
width the report shows it at (``continuation.plotting.displayed_font_px``).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import pytest

from continuation.plotting import (
    MIN_FONT_PX,
    REPORT_FIGURE_PX,
    displayed_font_px,
    png_font_px,
)


def test_displayed_size_closed_form():
    # 9 pt at 150 dpi = 18.75 px; a 2160-px PNG shown 1080 px wide halves it
    assert displayed_font_px(9.0, 2160, 150, 1080) == pytest.approx(9.375, rel=1e-15)
    assert displayed_font_px(9.0, 900, 150, 1080) == pytest.approx(18.75, rel=1e-15)


def _composite(fig_width_in: float, font_pt: float):
    from studies._common import new_figure

    fig = new_figure((fig_width_in, 0.8 * fig_width_in))
    for ax in fig.subplots(2, 2).ravel():
        ax.plot([0, 1], [0, 1], label="a curve")
        ax.set_xlabel("label")
        ax.legend(fontsize=font_pt)
    return fig


def test_save_figure_records_the_font_and_a_crowded_figure_fails_the_check(tmp_path):
    from studies._common import save_figure

    ok = save_figure(_composite(9.0, 7.0), tmp_path / "ok.png")  # the Fig. 21 layout
    assert png_font_px(ok) >= MIN_FONT_PX
    # the old tornado's proportions: 15 in wide, 7-pt labels -> about 5 px in the report
    bad = save_figure(_composite(15.0, 5.0), tmp_path / "bad.png")
    assert png_font_px(bad) < MIN_FONT_PX


def test_the_tornado_is_legible_at_report_width(tmp_path):
    from ship_models.analysis.sensitivity.figure import tornado_figure

    entries = [
        SimpleNamespace(key=f"section.coefficient_{i}", elasticity=(-1) ** i * 0.3 / (i + 1),
                        kind="physical", status="estimated")
        for i in range(36)
    ]  # fmt: skip
    sens = SimpleNamespace(entries=entries, Fn=0.30161, chi_c=math.radians(10.0))
    band = SimpleNamespace(
        contributions=[(e.key, abs(e.elasticity) * 0.01) for e in entries],
        band=(0.286, 0.317),
        sigma_linear=0.008,
    )
    png = tornado_figure(sens, tmp_path / "tornado.png", band=band)
    shown = png_font_px(png, REPORT_FIGURE_PX)
    assert shown is not None and shown >= MIN_FONT_PX


def test_the_report_shows_figures_at_the_width_the_check_assumes():
    from pathlib import Path

    css = (Path(__file__).resolve().parents[1] / "broachkit_cli" / "templates"
           / "report.html.j2").read_text()  # fmt: skip
    assert f"max-width: min(100%, {REPORT_FIGURE_PX}px)" in css
    assert "grid-template-columns: 1fr;" in css  # figures below the statement, full width
