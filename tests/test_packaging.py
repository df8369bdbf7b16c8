"""What ``pip install .`` (not editable) ships: the studies of the main job and the report's
template, so that the installed ``broachkit`` runs the full job without the source tree.

Static checks of ``pyproject.toml`` against the files (building a wheel takes a
network round-trip for the build backend); the install itself was run by hand:
``pip install --no-deps .`` into a fresh venv, then ``broachkit --only demo fig06_09``
from another folder imports every study from site-packages.
"""

from __future__ import annotations

import importlib
import tomllib
from pathlib import Path

from setuptools import find_packages

ROOT = Path(__file__).resolve().parents[1]


def test_studies_and_template_are_packaged() -> None:
    cfg = tomllib.loads((ROOT / "pyproject.toml").read_text())
    include = cfg["tool"]["setuptools"]["packages"]["find"]["include"]
    pkgs = set(find_packages(where=str(ROOT), include=include))
    assert {"studies", "broachkit_cli", "broachkit_cli.commands"} <= pkgs
    data = cfg["tool"]["setuptools"]["package-data"]["broachkit_cli"]
    assert "templates/*.j2" in data
    assert list((ROOT / "broachkit_cli" / "templates").glob("*.j2"))
    deps = " ".join(cfg["project"]["dependencies"])
    assert "jinja2" in deps


def test_every_step_of_the_main_job_is_a_module_of_the_package() -> None:
    from broachkit_cli.commands.reproduce import STUDY_STEPS

    for _, _, module in STUDY_STEPS:
        mod = importlib.import_module(f"studies.{module}")
        assert callable(mod.compute), module
