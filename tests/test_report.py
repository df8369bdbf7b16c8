"""``report.html`` of the main job, the step marker and the atomic result files.

The report is built from a real run of the two fastest steps (the engine demo and the
eigen study, a few seconds): its numbers must be the run's own (read back from the
step summaries), every figure it shows must exist, and a real headless browser
(Chromium via Selenium) must load every image. The browser test skips, saying why,
only when Chromium or Selenium is absent (``.ci/run`` installs both).
"""

from __future__ import annotations

import html
import json
import re
import shutil
from pathlib import Path

import pytest

from broachkit_cli.files import INCOMPLETE_MARKER, atomic_path, write_json
from broachkit_cli.main import main
from broachkit_cli.report import AT_LIMIT_MARGIN, is_code_sentence


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("job")
    assert main(["--out", str(out), "--only", "demo", "fig02_05", "fig06_09", "--json"]) == 0
    return out


def test_report_holds_the_runs_numbers_and_existing_figures(run: Path) -> None:
    page = (run / "report.html").read_text()
    assert "{{" not in page and "{%" not in page
    srcs = re.findall(r'<img src="([^"]+)"', page)
    assert srcs, "no figure in the report"
    for src in srcs:
        assert not src.startswith(("/", "http", "file:")), src  # relative links only
        assert (run / html.unescape(src)).is_file(), src
    eig = json.loads((run / "fig06_09" / "summary.json").read_text())
    for label, pt in eig["points"].items():
        # the eigen claim shows this run's unstable eigenvalue, formatted from the summary
        assert f"{pt['unstable_eigenvalue_nondim']:.3f}" in page, label
    # steps that did not run are reported as such, not as agreeing
    assert page.count('class="verdict not-run"') >= 5
    assert "agrees" in page and "differs" in page
    doc = json.loads((run / "reproduce.json").read_text())
    assert doc["report"] == str(run / "report.html")
    assert "fig06_09/fig06_eigenvalues_crest.png" in doc["figures"]
    assert set(doc["key_numbers"]) >= {"Fn_bvp", "Fn_bisection", "critical_curve_ends"}


def test_report_vessel_table_and_is_code_statement(run: Path) -> None:
    from ship_models.registry import get_vessel_data

    page = html.unescape((run / "report.html").read_text())
    data = get_vessel_data("purse_seiner")
    for key in ("particulars.L_pp", "loading.GM", "particulars.C_b"):
        assert key in page
    assert is_code_sentence(float(data.info["is_code_margin"])) in page


def test_is_code_sentence_agrees_with_the_sign_of_the_margin() -> None:
    assert "met (" in is_code_sentence(1e-3)
    assert "NOT met" not in is_code_sentence(1e-3)
    near = is_code_sentence(-0.5 * AT_LIMIT_MARGIN)
    assert "at the limit" in near and "missed" in near
    assert "NOT met" in is_code_sentence(-10 * AT_LIMIT_MARGIN)


def test_interrupted_step_leaves_a_marker_and_is_redone(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from broachkit_cli.commands import demo

    real = demo.compute

    def interrupted(out: Path) -> None:
        write_json(out / "summary.json", {"half": True})  # as if the step got far
        raise KeyboardInterrupt

    monkeypatch.setattr(demo, "compute", interrupted)
    assert main(["reproduce", "--out", str(tmp_path), "--only", "demo", "--no-report"]) == 130
    assert (tmp_path / "demo" / INCOMPLETE_MARKER).exists()
    monkeypatch.setattr(demo, "compute", real)
    capsys.readouterr()
    argv = ["reproduce", "--out", str(tmp_path), "--only", "demo", "--no-report", "--json"]
    assert main(argv) == 0
    doc = json.loads(capsys.readouterr().out)
    assert "demo" in doc["seconds"]  # redone, not skipped
    assert not (tmp_path / "demo" / INCOMPLETE_MARKER).exists()
    assert "half" not in json.loads((tmp_path / "demo" / "summary.json").read_text())


def test_atomic_file_is_untouched_when_writing_fails(tmp_path: Path) -> None:
    target = tmp_path / "r.csv"
    target.write_text("old\n")
    with pytest.raises(RuntimeError), atomic_path(target) as tmp:
        tmp.write_text("half")
        raise RuntimeError("interrupted")
    assert target.read_text() == "old\n"
    assert list(tmp_path.iterdir()) == [target]


def _chromium() -> tuple[str, str] | None:
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    driver = shutil.which("chromedriver")
    return (browser, driver) if browser and driver else None


def test_report_opens_in_a_headless_browser_with_every_image_loaded(run: Path) -> None:
    found = _chromium()
    if found is None:
        pytest.skip("Chromium/ChromeDriver absent: apt-get install chromium chromium-driver")
    webdriver = pytest.importorskip("selenium.webdriver", reason="selenium not installed")
    from selenium.webdriver.chrome.service import Service

    browser, driver_path = found
    opts = webdriver.ChromeOptions()
    opts.binary_location = browser
    for flag in (
        "--headless=new",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--disable-dev-shm-usage",
    ):
        opts.add_argument(flag)  # fmt: skip
    drv = webdriver.Chrome(service=Service(driver_path), options=opts)
    try:
        drv.set_page_load_timeout(60)
        drv.get((run / "report.html").resolve().as_uri())
        images = drv.execute_script(
            "return Array.from(document.images).map(i => "
            "[i.getAttribute('src'), i.complete, i.naturalWidth, i.naturalHeight]);"
        )
        title = drv.title
    finally:
        drv.quit()
    assert "Umeda" in title
    assert images, "the page shows no image"
    broken = [src for src, done, w, h in images if not (done and w > 0 and h > 0)]
    assert not broken, f"images not loaded: {broken}"


def test_every_csv_has_angles_in_degrees(run: Path) -> None:
    import csv

    import numpy as np

    from continuation.branch import Branch

    bare = {"chi", "phi", "delta", "r", "p_roll"}
    csvs = list(run.glob("fig*/*.csv"))
    assert csvs
    for path in csvs:
        with path.open() as fh:
            header = next(csv.reader(ln for ln in fh if not ln.startswith("#")))
        assert not bare & set(header), (path.name, header)
    # and the degrees are the branch's radians converted
    br = Branch.load(run / "fig02_05" / "branch_chi_c_crest.npz")
    with (run / "fig02_05" / "fixed_points_chi_c.csv").open() as fh:
        rows = list(csv.DictReader(ln for ln in fh if not ln.startswith("#")))
    crest = [r for r in rows if r["branch"] == "crest"]
    phi = np.array([float(r["phi_deg"]) for r in crest])
    np.testing.assert_allclose(phi, np.degrees(br.x[:, 5]), rtol=1e-12)
