"""Random and hostile input to every command and to the vessel loader (hypothesis).

Parse-level and fast: the library call each command makes is replaced by a probe
that records what the command would compute with and stops there. For any input,
either the command refuses it with exit status 2 and ONE line on stderr that names
an option (``--...``) or a vessel-file field (backticks), or it reaches the
computation with parameters that are physically possible (a wave no steeper than
1/7, a Froude number inside the vessel's resistance fit, a course within +-85 deg).
Never a traceback, never a silent acceptance of an impossible value.
"""

from __future__ import annotations

import copy
import math
import re
import tempfile
import tomllib
from pathlib import Path
from typing import Any

import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from broachkit_cli import options  # noqa: E402
from broachkit_cli.main import main  # noqa: E402
from ship_models.vessel import (  # noqa: E402
    BREAKING_STEEPNESS,
    SCHEMA,
    VesselFileError,
    load_vessel,
    parse_vessel,
)

DATA = Path(__file__).resolve().parents[1] / "ship_models" / "data"
FAST = settings(
    max_examples=60,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


class Reached(BaseException):
    """The command accepted its input and called the library (not an Exception, so the
    entry point's error handling lets it through)."""

    def __init__(self, what: str, **seen: Any) -> None:
        super().__init__(what)
        self.seen = seen


def _probe(what: str):
    def fn(*args: Any, **kwargs: Any) -> Any:
        raise Reached(what, args=args, kwargs=kwargs)

    return fn


@pytest.fixture
def probes(monkeypatch: pytest.MonkeyPatch, tmp_path_factory: pytest.TempPathFactory) -> None:
    """Stop every command where it would start computing (the library's entry points).

    Runs in an empty folder holding one file, ``README.md`` (an ``--out`` that is a file).
    """
    here = tmp_path_factory.mktemp("cwd")
    (here / "README.md").write_text("a file\n")
    monkeypatch.chdir(here)
    import ship_models.analysis as analysis
    import ship_models.analysis.critical as critical
    import ship_models.analysis.critical_bvp as critical_bvp
    import ship_models.analysis.critical_curve as critical_curve
    import ship_models.analysis.manifold as manifold
    from broachkit_cli.commands import demo, reproduce

    monkeypatch.setattr(analysis, "fixed_points", _probe("fixed_points"))
    monkeypatch.setattr(critical, "critical_fn", _probe("critical_fn"))
    monkeypatch.setattr(critical_bvp, "critical_fn_bvp", _probe("critical_fn_bvp"))
    monkeypatch.setattr(critical_curve, "critical_curve", _probe("critical_curve"))
    monkeypatch.setattr(manifold, "unstable_manifold", _probe("unstable_manifold"))
    monkeypatch.setattr(demo, "compute", _probe("demo"))
    monkeypatch.setattr(reproduce, "study_module", _probe("study"))


# ----------------------------------------------------------------- hostile values
NUMBERS = st.one_of(
    st.sampled_from(["nan", "inf", "-inf", "0", "-0", "1e308", "-1e308", "1e-320", "0.5",
                     "5", "-1", "0.3248", "0.14285714285714285", "0.1429", "90", "84.9"]),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.text(max_size=6),
)  # fmt: skip
PATHS = st.sampled_from(
    ["/proc/x", "/proc/x/y", "README.md", "/dev/null", "/", "", "out/../out", "\x00bad"]
)
VESSELS = st.one_of(
    st.sampled_from(
        ["purse_seiner", "kvlcc2", "nope", "", " ", "/etc/passwd", "/dev/zero", "x.toml",
         "/proc/self/status", "../", "purse_seiner_surge", "\x00"]
    ),
    st.text(max_size=8),
)  # fmt: skip

SHIP_OPTS = {"--chi-c": NUMBERS, "--h-over-lambda": NUMBERS, "--lambda-over-l": NUMBERS}
COMMANDS: dict[str, dict[str, Any]] = {
    "fixed-points": {**SHIP_OPTS, "--fn": NUMBERS},
    "manifold": {**SHIP_OPTS, "--fn": NUMBERS, "--eps": NUMBERS, "--t-max": NUMBERS,
                 "--capsize-angle": NUMBERS, "--out": PATHS},
    "critical": {**SHIP_OPTS, "--fn-min": NUMBERS, "--fn-max": NUMBERS, "--fn-guess": NUMBERS,
                 "--tol": NUMBERS, "--t-max": NUMBERS,
                 "--method": st.sampled_from(["bisection", "bvp", "both", "x"])},
    "critical-curve": {"--chi-c": st.one_of(NUMBERS, st.sampled_from(
        ["0:30", "30:0", "0:1e9:1e-9", "0:10:0", "a,b", "1,,2", "0:84", "0:85", "-5:5:2.5"])),
        "--h-over-lambda": NUMBERS, "--lambda-over-l": NUMBERS, "--fn-guess": NUMBERS,
        "--out": PATHS, "--workers": st.sampled_from(["0", "-1", "1", "2", "x", "1.5"])},
    "demo": {"--out": PATHS},
    "reproduce": {"--out": PATHS, "--only": st.sampled_from(["demo", "fig99", "fig06_09"])},
}  # fmt: skip


@st.composite
def argvs(draw: Any) -> list[str]:
    cmd = draw(st.sampled_from(sorted(COMMANDS)))
    opts = COMMANDS[cmd]
    chosen = draw(st.lists(st.sampled_from(sorted(opts)), unique=True, max_size=4))
    argv = [cmd]
    if "--vessel" not in chosen and cmd not in ("demo", "reproduce") and draw(st.booleans()):
        argv += ["--vessel", draw(VESSELS)]
    for opt in chosen:
        argv += [f"{opt}={draw(opts[opt])}"]
    return argv


def _check_params(params: Any) -> None:
    """What a command passes on must be physically possible."""
    p = params.as_dict()
    assert 0.0 < p["H_over_lambda"] <= BREAKING_STEEPNESS
    lo, hi = options.LAMBDA_OVER_L_RANGE
    assert lo <= p["lambda_over_L"] <= hi
    assert 0.0 < p["Fn"] <= 0.65
    assert abs(p["chi_c"]) < math.radians(options.CHI_C_MAX_DEG)


def _outcome(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[Any, str]:
    try:
        code: Any = main(argv)
    except SystemExit as exc:  # argparse's usage errors
        code = exc.code
    except Reached as hit:
        code = hit
    err = capsys.readouterr().err
    return code, err


@FAST
@given(argv=argvs())
def test_every_command_refuses_or_accepts_sanely(argv, capsys, probes):
    code, err = _outcome(argv, capsys)
    assert "Traceback" not in err, (argv, err)
    if isinstance(code, Reached):
        for a in [*code.seen["args"], *code.seen["kwargs"].values()]:
            if hasattr(a, "as_dict") and hasattr(a, "replace"):
                _check_params(a)
        return
    assert code == 2, (argv, code, err)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, (argv, err)
    assert re.search(r"--[a-z]|`[a-z_]+\.[A-Za-z_]+`|argument|COMMAND|invalid choice", err), err


@pytest.mark.parametrize(
    ("argv", "names"),
    [
        (["fixed-points", "--h-over-lambda", "0.5"], "--h-over-lambda"),
        (["critical", "--fn-max", "5"], "--fn-max"),
        (["manifold", "--out", "/proc/x"], "--out"),
        (["demo", "--out", "README.md"], "--out"),
        (["critical-curve", "--out", "/proc/x"], "--out"),
        (["reproduce", "--out", "/proc/x"], "--out"),
        (["--out", "/proc/x"], "--out"),
        (["fixed-points", "--vessel", "nope"], "--vessel"),
        (["fixed-points", "--fn", "nan"], "--fn"),
        (["critical", "--fn-min", "0.35", "--fn-max", "0.3"], "--fn-min"),
        # a range of 1e18 values is refused before it is built (found by hypothesis:
        # it was a MemoryError, exit 1)
        (["critical-curve", "--chi-c=0:1e9:1e-9"], "--chi-c"),
        (["critical-curve", "--chi-c=0:1e308:1e-308"], "--chi-c"),
        (["critical-curve", "--workers", "0"], "--workers"),
        (["sweep", "courses", "--chi-c", "0:1:1e-12", "--out", "OUT"], "--chi-c"),
        (
            ["sweep", "surface", "--h-over-lambda", "0.02:0.1:99999999999", "--out", "OUT"],
            "--h-over-lambda",
        ),
        (["sweep", "boundary", "--positions", "99999999999", "--out", "OUT"], "--positions"),
        (["sensitivity", "--curve", "0:30:1e-15"], "--curve"),
        (["sensitivity", "--chi-c", "100"], "--chi-c"),
        (["sensitivity", "--samples", "-1"], "--samples"),
        (["calibrate", "--target", "Fn=abc"], "--target"),
        (["calibrate", "--target", "speed=0.3"], "fn_crit=VALUE"),
        (["calibrate", "--target", "fn_crit=0.32", "--curve", "0:30:-5"], "--curve"),
        (["periodic", "--fn", "nan"], "--fn"),
        (["periodic", "--chi-c", "400"], "--chi-c"),
        (["periodic-branch", "--fn", "0.1:0.35", "--chi-c", "0:20"], "exactly one range"),
        (["periodic-branch", "--fn", "0.3:0.1"], "--fn range must increase"),
        (["periodic-branch", "--fn", "0.1:x"], "--fn must be a number or a range"),
        (["periodic-branch", "--fn", "0.3", "--chi-c", "10:10"], "--chi-c range"),
        (["periodic-branch", "--fn", "0.3", "--chi-c", "0:30", "--compare"], "--compare"),
    ],
)
def test_known_mistakes_name_the_option(argv, names, capsys, probes, tmp_path):
    argv = [str(tmp_path / "out") if a == "OUT" else a for a in argv]
    code, err = _outcome(argv, capsys)
    assert code == 2 and names in err and len(err.strip().splitlines()) == 1, err
    assert "Traceback" not in err


def test_out_folder_checked_before_computing(capsys, probes):
    # the probe would be reached first if the folder were checked after computing
    for cmd in (["manifold"], ["critical-curve"], ["demo"], ["reproduce"]):
        code, err = _outcome([*cmd, "--out", "/proc/x"], capsys)
        assert code == 2 and "--out" in err


def test_verbose_shows_the_traceback(capsys):
    code, err = _outcome(["-v", "fixed-points", "--vessel", "nope"], capsys)
    assert code == 2 and "Traceback" in err
    code, err = _outcome(["fixed-points", "--vessel", "nope", "--verbose"], capsys)
    assert code == 2 and "Traceback" in err


def test_default_command_takes_options():
    from broachkit_cli.main import _load_commands, with_default_command

    cmds = _load_commands()
    assert with_default_command([], cmds) == ["reproduce"]
    assert with_default_command(["--out", "X"], cmds) == ["reproduce", "--out", "X"]
    assert with_default_command(["-v", "--out", "X"], cmds) == ["-v", "reproduce", "--out", "X"]
    assert with_default_command(["demo"], cmds) == ["demo"]
    assert with_default_command(["-h"], cmds) == ["-h"]


# ----------------------------------------------------------------- vessel loader
BASE = tomllib.loads((DATA / "purse_seiner.toml").read_text())
FIELDS = [(sec, key) for sec, tab in BASE.items() if sec != "vessel" for key in tab]
VALUES = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -1.0, 1e12, 1e-12, 1000.0, -997.0, 1e300]),
    st.integers(min_value=-(10**20), max_value=10**20),
    st.text(max_size=5),
    st.booleans(),
    st.none(),
)


@st.composite
def mutated(draw: Any) -> tuple[dict[str, Any], str]:
    doc = copy.deepcopy(BASE)
    n = draw(st.integers(1, 3))
    keys = []
    for _ in range(n):
        sec, key = draw(st.sampled_from(FIELDS))
        if not isinstance(doc[sec].get(key), dict):  # dropped or replaced earlier
            continue
        keys.append(f"{sec}.{key}")
        what = draw(st.sampled_from(["value", "unit", "status", "drop", "table", "extra"]))
        if what == "value":
            v = draw(VALUES)
            if v is None:
                continue
            doc[sec][key]["value"] = v
        elif what == "unit":
            doc[sec][key]["unit"] = draw(st.sampled_from(["km", "", "ft", "deg", "m", "-", "s"]))
        elif what == "status":
            doc[sec][key]["status"] = draw(st.sampled_from(["guessed", "", "measured"]))
        elif what == "drop":
            del doc[sec][key]
        elif what == "table":
            doc[sec][key] = draw(VALUES)
        else:
            doc[sec][key]["oops"] = 1
    return doc, ",".join(keys)


@FAST
@given(case=mutated())
def test_vessel_loader_refuses_with_the_field_or_accepts_in_range(case):
    doc, keys = case
    try:
        v = parse_vessel(doc)
    except VesselFileError as exc:
        msg = str(exc)
        assert "\n" not in msg
        assert re.search(r"`[A-Za-z_][\w.]*`", msg), msg
        return
    # accepted: every value is finite and inside its schema range (SI)
    for key, c in v.coefficients.items():
        sec, name = key.split(".", 1)
        spec = SCHEMA[sec][name]
        assert math.isfinite(c.value), key
        assert spec.low <= c.value * _si(key, c.unit) <= spec.high, (key, c)


def _si(key: str, unit: str) -> float:
    from ship_models.vessel import _si_factor

    return _si_factor(key, unit)


@FAST
@given(text=st.one_of(st.text(max_size=200), st.sampled_from(["", "[vessel]", "x = 1"])))
def test_vessel_file_of_random_text_is_refused_in_one_line(text):
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "v.toml"
        p.write_text(text, encoding="utf-8", errors="surrogatepass")
        with pytest.raises(ValueError) as info:
            load_vessel(p)
        assert "\n" not in str(info.value).strip()


@pytest.mark.parametrize(
    ("section", "key", "value", "field"),
    [
        ("loading", "GM", 1000.0, "loading.GM"),
        ("particulars", "L_pp", 1e12, "particulars.L_pp"),
        ("waves", "H_over_lambda", 0.5, "waves.H_over_lambda"),
        ("particulars", "B", 1e-3, "particulars.B"),
    ],
)
def test_impossible_vessels_name_the_field(section, key, value, field, capsys):
    doc = copy.deepcopy(BASE)
    doc[section][key]["value"] = value
    with pytest.raises(VesselFileError, match=re.escape(f"`{field}`")):
        parse_vessel(doc)


def test_fn_range_without_an_answer_says_so(capsys):
    """Both ends capsize: one line naming the range, exit 1, and no NaN printed as an answer."""
    import json

    argv = ["critical", "--chi-c", "10", "--fn-min", "0.31", "--fn-max", "0.4", "--tol", "0.01"]
    assert main(argv) == 1
    out, err = capsys.readouterr()
    assert out == "" and "nan" not in err.lower()
    assert len(err.strip().splitlines()) == 1 and "--fn-min/--fn-max" in err
    assert "NO_BRACKET" in err
    assert main([*argv, "--json"]) == 1
    doc = json.loads(capsys.readouterr().out)  # strict JSON: no NaN
    assert doc["Fn"] is None and doc["status"] == "NO_BRACKET"


@pytest.mark.parametrize("value", ["0", "-3", "x", "1.5"])
def test_a_bad_workers_variable_is_named(value, capsys, probes, monkeypatch):
    """``$BROACHKIT_WORKERS`` (the worker count when ``--workers`` is not given) is
    checked like the option and named in the one-line error."""
    monkeypatch.setenv("BROACHKIT_WORKERS", value)
    code, err = _outcome(["reproduce", "--only", "demo"], capsys)
    assert code == 2 and "BROACHKIT_WORKERS" in err and len(err.strip().splitlines()) == 1, err
    monkeypatch.setenv("BROACHKIT_WORKERS", "2")
    code, err = _outcome(["reproduce", "--only", "demo", "--workers", "0"], capsys)
    assert code == 2 and "--workers" in err, err
