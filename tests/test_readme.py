"""The README's code example runs and its assertions hold (Brusselator: Hopf at B = 1 + A^2)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"


def _python_blocks() -> list[str]:
    return re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)


def test_readme_has_the_two_setup_commands() -> None:
    text = README.read_text()
    assert 'pip install -e ".[hull]" && broachkit' in text
    assert 'pip install -e ".[test,hull]" && python -m pytest' in text


@pytest.mark.parametrize("block", _python_blocks())
def test_readme_example_runs(block: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    namespace: dict[str, object] = {}
    exec(compile(block, str(README), "exec"), namespace)  # noqa: S102 - our own README
    assert (tmp_path / "brusselator.csv").exists()
