"""Every command in the README's code blocks runs as written (issue 27: the README cannot
drift from the command line).

Each ``broachkit ...`` line of a ```bash block is parsed by the real parser (every option
exists, every value has its type); the quick ones run for real, the long ones in a short
form (a smaller range or grid, listed here) in the ``slow`` run. The two setup commands
are the ones CI runs.
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"


def _blocks() -> list[str]:
    return re.findall(r"```bash\n(.*?)```", README.read_text(), flags=re.S)


def _commands() -> list[list[str]]:
    out = []
    for block in _blocks():
        for line in block.splitlines():
            if line.startswith("broachkit"):
                out.append(shlex.split(line, comments=True)[1:])
    return out


COMMANDS = _commands()
IDS = [" ".join(c)[:60] for c in COMMANDS]

#: Commands run for real in the default run (seconds each).
QUICK = {"fixed-points", "manifold", "vessels", "demo"}

#: Short forms of the long commands (option -> value replaced), for the slow run.
SHORT = {
    "--chi-c": {"0:40": "10:20"},
    "--positions": {"21": "2", "4": "1"},
    "--fn": {"0.1:0.35": "0.25:0.3"},
}


def test_the_readme_has_the_two_commands_ci_runs():
    text = README.read_text()
    ci = (ROOT / ".ci" / "run").read_text()
    install, tests = (b.strip() for b in _blocks()[:2])
    assert install.startswith("pip install -e ") and install.endswith("&& broachkit")
    assert tests.startswith("pip install -e ") and tests.endswith("&& python -m pytest")
    assert f"bash -c '{tests}'" in ci
    assert "broachkit" in text


def test_the_readme_lists_commands():
    names = {c[0] for c in COMMANDS}
    assert {"fixed-points", "manifold", "critical", "critical-curve", "sweep", "assess"} <= names


@pytest.mark.parametrize("argv", COMMANDS, ids=IDS)
def test_every_readme_command_parses(argv):
    from broachkit_cli.main import _load_commands, build_parser, with_default_command

    cmds = _load_commands()
    ns = build_parser(cmds).parse_args(with_default_command(list(argv), cmds))
    assert ns.command == argv[0]


def _run(argv, tmp_path, monkeypatch, capsys):
    from broachkit_cli.main import main

    monkeypatch.chdir(tmp_path)
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out


QUICK_CMDS = [(c, i) for c, i in zip(COMMANDS, IDS, strict=True) if c[0] in QUICK]
LONG_CMDS = [(c, i) for c, i in zip(COMMANDS, IDS, strict=True) if c[0] not in QUICK]


@pytest.mark.parametrize("argv", [c for c, _ in QUICK_CMDS], ids=[i for _, i in QUICK_CMDS])
def test_the_quick_readme_commands_run_as_written(argv, tmp_path, monkeypatch, capsys):
    argv = [str(ROOT / a) if a.endswith(".toml") and "/" in a else a for a in argv]
    code, out = _run(argv, tmp_path, monkeypatch, capsys)
    assert code == 0, out.err
    assert out.out.strip()


def _short(argv: list[str]) -> list[str]:
    out = list(argv)
    for i, a in enumerate(out[:-1]):
        if a in SHORT and out[i + 1] in SHORT[a]:
            out[i + 1] = SHORT[a][out[i + 1]]
    return out


@pytest.mark.slow
@pytest.mark.parametrize("argv", [c for c, _ in LONG_CMDS], ids=[i for _, i in LONG_CMDS])
def test_the_long_readme_commands_run_in_short_form(argv, tmp_path, monkeypatch, capsys):
    if "--scatter" in argv:  # the user's scatter table (not shipped): a one-sea-state file
        (tmp_path / argv[argv.index("--scatter") + 1]).write_text("Hs\\Tz, 8.5\n6.5, 1\n")
    code, out = _run(_short(argv), tmp_path, monkeypatch, capsys)
    assert code in (0, 1), out.err  # 1: an honest non-SUCCESS status, never a crash (2)
    assert "Traceback" not in out.err
