"""``broachkit`` / ``broachkit reproduce``: the main job runs, writes its outputs, and resumes.

A smoke test on the two fastest steps (the full run takes about 1.5 minutes and is
exercised by `broachkit` itself): the engine demo must locate the Brusselator Hopf
point at the closed form B = 1 + A^2 = 2, and the eigen study must report saddle
index 1 at both fixed points (the paper's Figs. 6-7 statement, also true for our vessel).
"""

from __future__ import annotations

import json
import os
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


_FAKE_STUDY = """
import json, os
from pathlib import Path

def compute(out, progress=None, workers=None):
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    if os.environ.get("FAKE_FAIL") == out.name:
        raise RuntimeError("fake failure")
    doc = {"pid": os.getpid(), "workers_env": os.environ.get("BROACHKIT_WORKERS"),
           "workers": workers}
    (out / "summary.json").write_text(json.dumps(doc))
    return doc
"""


def _fake_studies(folder: Path) -> Path:
    folder.mkdir()
    for module in ("fig10_15_manifolds", "fig21_23_connection", "fig16_22_sudden_change"):
        (folder / f"{module}.py").write_text(_FAKE_STUDY)
    return folder


def test_reproduce_runs_other_steps_beside_the_sweep_step(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """--workers 2: the sweep step here, the others as tasks of the job's worker pool;
    same results."""
    studies = _fake_studies(tmp_path / "studies")
    out = tmp_path / "out"
    args = ["reproduce", "--out", str(out), "--studies", str(studies), "--no-report", "--json"]
    steps = ["--only", "fig10_15", "fig21_23", "fig16_22"]
    assert main([*args, *steps, "--workers", "2"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["steps"] == ["fig10_15", "fig21_23", "fig16_22"]
    assert doc["workers"] == 2
    pids = {k: json.loads((out / k / "summary.json").read_text())["pid"] for k in doc["steps"]}
    assert pids["fig16_22"] == os.getpid()
    assert os.getpid() not in (pids["fig10_15"], pids["fig21_23"])
    for k in doc["steps"]:
        assert not (out / k / ".incomplete").exists()
        # the count reaches the sweep step as an argument, never through the environment
        assert json.loads((out / k / "summary.json").read_text())["workers_env"] is None
    assert json.loads((out / "fig16_22" / "summary.json").read_text())["workers"] == 2
    # one worker: everything in this process
    assert main([*args, *steps, "--workers", "1", "--force"]) == 0
    capsys.readouterr()
    for k in doc["steps"]:
        assert json.loads((out / k / "summary.json").read_text())["pid"] == os.getpid()
    # a failing background step: one line, non-zero, the failed step is not marked done
    monkeypatch.setenv("FAKE_FAIL", "fig21_23")
    assert main([*args, *steps, "--workers", "2", "--force"]) != 0
    assert "fig21_23" in capsys.readouterr().err
    assert (out / "fig21_23" / ".incomplete").exists()


def test_side_steps_are_submitted_heaviest_first() -> None:
    from broachkit_cli.commands.reproduce import STEP_WEIGHTS, _heaviest_first

    todo = [(k, None) for k in STEP_WEIGHTS] + [("other", None)]
    order = [k for k, _ in _heaviest_first(todo)]
    assert sorted(order) == sorted(k for k, _ in todo)  # each once
    weights = [STEP_WEIGHTS.get(k, 5.0) for k in order]
    assert weights == sorted(weights, reverse=True)
    assert order[0] == max(STEP_WEIGHTS, key=STEP_WEIGHTS.__getitem__)


def test_reproduce_bad_workers_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["reproduce", "--out", str(tmp_path), "--only", "demo", "--workers", "0"]) == 2
    assert "--workers" in capsys.readouterr().err
