"""Every command in README.md's ```bash blocks is run by a test, so the README cannot drift.

The blocks are parsed from the README itself. Each ``broachkit`` command must

1. parse as written with the real argument parser (every option it names exists), and
2. be listed in :data:`RUNS` with the arguments it is run with here: as written, or a
   short form of it where the written one takes long (fewer positions, one course,
   one wavelength); a README command missing from :data:`RUNS` fails the test.

Commands that take more than a few seconds even in short form are marked ``slow``.
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

from broachkit_cli.main import _load_commands, build_parser, main, with_default_command

README = Path(__file__).resolve().parents[1] / "README.md"
VESSEL_FILE = Path(__file__).resolve().parents[1] / "ship_models" / "data" / "purse_seiner.toml"

#: Setup commands of the README that are not ``broachkit`` (run by the CI itself).
SETUP = {"pip install -e .", 'pip install -e ".[test]"', "python -m pytest"}

#: README command (as written, comment removed) -> (argv run here, slow?).
RUNS: dict[str, tuple[list[str], bool]] = {
    "broachkit": (["reproduce", "--only", "demo", "--out", "out"], False),
    "broachkit fixed-points --fn 0.3248 --chi-c 10 --json": (
        ["fixed-points", "--fn", "0.3248", "--chi-c", "10", "--json"], False),
    "broachkit manifold --fn 0.30155 --chi-c 10 --json": (
        ["manifold", "--fn", "0.30155", "--chi-c", "10", "--json"], True),
    "broachkit critical --chi-c 10 --method bisection --json": (
        ["critical", "--chi-c", "10", "--method", "bisection", "--json"], True),
    "broachkit critical --chi-c 10 --method bvp --json": (
        ["critical", "--chi-c", "10", "--method", "bvp", "--json"], False),
    "broachkit critical-curve --chi-c 0:50 --json": (
        ["critical-curve", "--chi-c", "0:1", "--json"], True),
    "broachkit cycles --chi-c 10 --compare": (["cycles", "--chi-c", "10", "--compare"], True),
    "broachkit periodic --fn 0.3 --chi-c 45 --shooting --json": (
        ["periodic", "--fn", "0.3", "--chi-c", "45", "--shooting", "--json"], True),
    "broachkit periodic-branch --chi-c 10 --fn 0.1:0.35 --json": (
        ["periodic-branch", "--chi-c", "10", "--fn", "0.1:0.35", "--json"], True),
    "broachkit sensitivity --chi-c 10 --json": (
        ["sensitivity", "--chi-c", "10", "--keys", "hydrodynamics.wave_surge_scale", "--json"],
        True),
    "broachkit calibrate --target fn_crit=0.32475 --chi-c 10 --coefficient wave_surge_scale": (
        ["calibrate", "--target", "fn_crit=0.32475", "--chi-c", "10", "--coefficient",
         "wave_surge_scale"], True),
    "broachkit sweep boundary --chi-c 10 --initial fn=0.1,chi_c=0 --positions 21 --workers 2 "
    "--out b": (
        ["sweep", "boundary", "--chi-c", "10", "--initial", "fn=0.1,chi_c=0", "--positions", "1",
         "--tol", "1e-3", "--no-map", "--serial", "--out", "b"], True),
    "broachkit sweep boundary --chi-c 10 --positions 4 --tol 1e-6 --method bvp --out bb": (
        ["sweep", "boundary", "--chi-c", "10", "--positions", "1", "--tol", "1e-3", "--no-map",
         "--method", "bvp", "--serial", "--out", "bb"], True),
    "broachkit sweep surface --chi-c 10 --out surface": (
        ["sweep", "surface", "--chi-c", "10", "--h-over-lambda", "0.1087", "--lambda-over-l",
         "1.5", "--check", "0", "--serial", "--out", "surface"], True),
    "broachkit vessels list": (["vessels", "list"], False),
    "broachkit vessels show purse_seiner --json": (
        ["vessels", "show", "purse_seiner", "--json"], False),
    "broachkit vessels validate FILE": (["vessels", "validate", str(VESSEL_FILE)], False),
    "broachkit demo": (["demo"], False),
}  # fmt: skip


def readme_commands() -> list[str]:
    """Every command of the README's ```bash blocks (comments removed, `&&` and the
    `a | b | c` shorthand of sub-commands expanded)."""
    cmds: list[str] = []
    for block in re.findall(r"```bash\n(.*?)```", README.read_text(), flags=re.S):
        for line in block.splitlines():
            line = re.sub(r"\s+#.*$", "", line).strip()
            for part in (p.strip() for p in line.split("&&")):
                if not part:
                    continue
                if part.startswith("broachkit ") and " | " in part:
                    head, *alts = part.split(" | ")
                    prefix = " ".join(head.split()[:2])  # "broachkit vessels"
                    cmds.append(head)
                    cmds += [f"{prefix} {alt.strip()}" for alt in alts]
                else:
                    cmds.append(part)
    return cmds


def _broachkit_commands() -> list[str]:
    return [c for c in readme_commands() if c == "broachkit" or c.startswith("broachkit ")]


def test_every_readme_command_is_known_here():
    cmds = readme_commands()
    assert len(_broachkit_commands()) >= 15
    for c in cmds:
        assert c in RUNS or c in SETUP, f"README command without a test: {c!r} (add it to RUNS)"


@pytest.mark.parametrize("command", _broachkit_commands())
def test_every_readme_command_parses_as_written(command):
    cmds = _load_commands()
    parser = build_parser(cmds)
    argv = shlex.split(command)[1:]
    argv = [str(VESSEL_FILE) if a == "FILE" else a for a in argv]
    args = parser.parse_args(with_default_command(argv, cmds))  # exits 2 on an unknown option
    assert args.command in cmds


@pytest.mark.parametrize(
    "command",
    [pytest.param(c, marks=pytest.mark.slow) if RUNS[c][1] else c for c in RUNS],
)
def test_readme_command_runs(command, tmp_path, monkeypatch, capsys):
    assert command in _broachkit_commands(), f"{command!r} is no longer in the README"
    monkeypatch.chdir(tmp_path)
    rc = main(RUNS[command][0])
    out = capsys.readouterr()
    assert rc == 0, out.err
    assert "Traceback" not in out.err
