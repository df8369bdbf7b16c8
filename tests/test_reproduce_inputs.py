"""``broachkit reproduce`` reuses a finished step only for the inputs that made it.

Issue 28: after the vessel file's H/lambda was edited from 1/9.2 to 1/12 the main job
skipped all 8 steps and printed the old number. Each step now records the vessel
file's content, the settings and the code version it was computed from; a rerun
recomputes exactly the steps whose record differs and says why.

Study scripts are stand-ins (``--studies``) that read the vessel file, so every run is
fast and the result visibly follows its input; the engine demo is the real one.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from broachkit_cli.commands import reproduce
from broachkit_cli.main import main

_STUDY = """
import hashlib, json, os
from pathlib import Path
{extra}

def compute(out, progress=None):
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    text = Path(os.environ["FAKE_VESSEL"]).read_text()
    doc = {{"H_over_lambda": float(text.split("=")[1]), "version": {version}}}
    (out / "summary.json").write_text(json.dumps(doc))
    return doc
"""


def _write_study(folder: Path, module: str, version: int = 1, extra: str = "") -> None:
    (folder / f"{module}.py").write_text(_STUDY.format(version=version, extra=extra))


@pytest.fixture
def job(tmp_path, monkeypatch, capsys):
    studies = tmp_path / "studies"
    studies.mkdir()
    (studies / "_shared.py").write_text("SCALE = 1\n")
    _write_study(studies, "fig02_05_fixed_points", extra="import _shared  # noqa: F401")
    _write_study(studies, "fig06_09_eigen")
    vessel = tmp_path / "vessel.toml"
    vessel.write_text(f"H_over_lambda = {1 / 9.2!r}\n")
    monkeypatch.setenv("FAKE_VESSEL", str(vessel))
    monkeypatch.syspath_prepend(str(studies))  # the stand-ins import their helper by name
    monkeypatch.setattr(reproduce, "vessel_file", lambda: vessel)
    out = tmp_path / "out"

    def run() -> dict:
        argv = ["reproduce", "--out", str(out), "--only", "demo", "fig02_05", "fig06_09",
                "--studies", str(studies), "--workers", "1", "--no-report", "--json"]  # fmt: skip
        assert main(argv) == 0
        return json.loads(capsys.readouterr().out)

    return run, studies, vessel, out


def _recomputed(doc: dict) -> set[str]:
    return {k for k, v in doc["reuse"].items() if not v["reused"]}


def test_a_changed_input_recomputes_exactly_the_steps_it_affects(job, capsys):
    run, studies, vessel, out = job
    first = run()
    assert _recomputed(first) == {"demo", "fig02_05", "fig06_09"}
    assert first["reuse"]["demo"]["reason"] == "not run before"
    for step in ("demo", "fig02_05", "fig06_09"):
        assert (out / step / "inputs.json").is_file()

    again = run()  # nothing changed: everything reused, and why that is valid
    assert _recomputed(again) == set() and again["seconds"] == {}
    assert again["reuse"]["fig02_05"]["reason"].startswith("same vessel file (sha256 ")
    assert again["reuse"]["demo"]["reason"] == "no vessel, same settings and code"

    # the vessel file edited (H/lambda 1/9.2 -> 1/12): the studies, not the engine demo
    vessel.write_text(f"H_over_lambda = {1 / 12!r}\n")
    doc = run()
    assert _recomputed(doc) == {"fig02_05", "fig06_09"}
    assert doc["reuse"]["fig06_09"]["reason"] == "the vessel file changed"
    summary = json.loads((out / "fig06_09" / "summary.json").read_text())
    assert summary["H_over_lambda"] == pytest.approx(1 / 12, rel=1e-15)

    # one study's code: that step only
    _write_study(studies, "fig06_09_eigen", version=2)
    doc = run()
    assert _recomputed(doc) == {"fig06_09"}
    assert doc["reuse"]["fig06_09"]["reason"] == "code changed (study)"

    # a helper one study imports: the steps that import it
    (studies / "_shared.py").write_text("SCALE = 2\n")
    assert _recomputed(run()) == {"fig02_05"}

    # another study folder is another setting
    other = studies.parent / "other"
    other.mkdir()
    for f in studies.iterdir():
        (other / f.name).write_bytes(f.read_bytes())
    argv = ["reproduce", "--out", str(out), "--only", "fig06_09", "--studies", str(other),
            "--workers", "1", "--no-report", "--json"]  # fmt: skip
    assert main(argv) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["reuse"]["fig06_09"] == {"reused": False, "reason": "settings changed (studies)"}


def test_a_step_without_a_record_of_its_inputs_is_recomputed(job, capsys):
    run, _, _, out = job
    run()
    (out / "fig02_05" / "inputs.json").unlink()  # e.g. a folder from an older broachkit
    doc = run()
    assert _recomputed(doc) == {"fig02_05"}
    assert doc["reuse"]["fig02_05"]["reason"] == "no record of the inputs it was computed from"


def test_the_summary_names_reused_and_recomputed_steps(job, capsys):
    run, _, vessel, out = job
    run()
    vessel.write_text(f"H_over_lambda = {1 / 12!r}\n")
    argv = ["reproduce", "--out", str(out), "--only", "demo", "fig02_05", "fig06_09",
            "--studies", str(job[1]), "--workers", "1", "--no-report"]  # fmt: skip
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "reused from an earlier run: demo (no vessel, same settings and code" in text
    assert "recomputed: fig02_05, fig06_09 (the vessel file changed)" in text
