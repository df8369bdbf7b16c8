"""The guides in ``docs/`` run as written: every code block, in order.

``python`` blocks are executed in one namespace per guide (their ``assert``s are the
guide's checks against closed forms or the file it wrote); each ``$ broachkit ...``
line of a ``console`` block goes through the command line's entry point and must
exit with 0.
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

from broachkit_cli.main import main

DOCS = Path(__file__).resolve().parents[1] / "docs"
GUIDES = sorted(DOCS.glob("*.md"))


def _blocks(path: Path) -> list[tuple[str, str]]:
    return re.findall(r"```(python|console)\n(.*?)```", path.read_text(), flags=re.S)


def test_there_are_the_guides_with_code() -> None:
    # the two first steps and one guide per extension point (README, Architecture)
    names = {p.name for p in GUIDES}
    assert {
        "your_own_vessel.md",
        "engine_on_your_own_ode.md",
        "vessel_with_own_wave_forces.md",
        "new_continuation_problem.md",
        "your_own_sweep.md",
    } <= names
    for p in GUIDES:
        assert any(kind == "python" for kind, _ in _blocks(p)), p.name


@pytest.mark.parametrize("guide", GUIDES, ids=lambda p: p.stem)
def test_guide_runs(
    guide: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture
) -> None:
    monkeypatch.chdir(tmp_path)
    namespace: dict[str, object] = {"__name__": f"guide_{guide.stem}"}
    for kind, code in _blocks(guide):
        if kind == "python":
            exec(compile(code, str(guide), "exec"), namespace)  # noqa: S102 - our own docs
            continue
        for line in code.splitlines():
            if line.startswith("$ broachkit "):
                argv = shlex.split(line[len("$ broachkit ") :])
                code_ = main(argv)
                err = capsys.readouterr().err
                assert code_ == 0, (line, err)
