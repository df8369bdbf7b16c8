"""``broachkit`` / ``broachkit reproduce``: the main job runs, writes its outputs, and resumes.

A smoke test on the two fastest steps (the full run takes about 1.5 minutes and is
exercised by `broachkit` itself): the engine demo must locate the Brusselator Hopf
point at the closed form B = 1 + A^2 = 2, and the eigen study must report saddle
index 1 at both fixed points (the paper's Figs. 6-7 statement, also true for our vessel).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from broachkit_cli.main import main


def test_reproduce_runs_writes_and_resumes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    assert main(["reproduce", "--out", str(out), "--only", "demo", "fig06_09", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["steps"] == ["demo", "fig06_09"]
    demo = json.loads((out / "demo" / "summary.json").read_text())
    (hopf,) = demo["brusselator"]["hopf"]
    assert hopf["B"] == pytest.approx(2.0, abs=1e-8)
    assert hopf["omega"] == pytest.approx(1.0, abs=1e-8)
    assert (out / "demo" / "demo.png").stat().st_size > 0
    eig = json.loads((out / "fig06_09" / "summary.json").read_text())
    assert {name: pt["saddle_index"] for name, pt in eig["points"].items()} == {
        "crest": 1,
        "trough": 1,
    }
    assert list((out / "fig06_09").glob("*.png"))
    assert list((out / "fig06_09").glob("*.csv"))
    # a second run skips the finished steps and reports the same results
    assert main(["reproduce", "--out", str(out), "--only", "demo", "fig06_09", "--json"]) == 0
    again = json.loads(capsys.readouterr().out)
    assert again["steps"] == ["demo", "fig06_09"]
    assert again["seconds"] == {}


def test_reproduce_unknown_step_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["reproduce", "--out", str(tmp_path), "--only", "fig99"]) == 2
    assert "--only" in capsys.readouterr().err
