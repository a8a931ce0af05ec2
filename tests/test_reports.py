"""Reports of every command (``--report``) and of any output folder (``rodlab report DIR``), the figures they
embed, and the wording of a finding's evidence. The pages are rendered in headless Chromium; in CI (CI=true,
where .ci/run installs Chromium) a missing browser fails the test instead of skipping it."""
from __future__ import annotations

import json
import re

import numpy as np
import pytest

from rodlab.app.cli.main import main


def _run(*argv) -> int:
    try:
        return main([str(a) for a in argv])
    except SystemExit as e:              # argparse refusals
        return int(e.code)


@pytest.fixture(scope="module")
def user_run(tmp_path_factory):
    """A user's own runs, each with --report: frame compliance, rig simulate -> fit -> diagnose, a campaign with
    a wrongly recorded clamping position -> calibrate, compare, diagnose; a small sweep."""
    d = tmp_path_factory.mktemp("user")
    sim = d / "fea" / "rod1.compliance.json"
    assert _run("fea", "rod1", "--model", "frame", "-o", sim, "--report") == 0
    assert _run("compliance", "rod2", "-o", d / "calc" / "rod2.compliance.json", "--report") == 0
    rec = d / "data" / "r.rig.csv"
    assert _run("rig", "simulate", "--sim", sim, "--effect", "friction", "--seed", 3, "-o", rec) == 0
    assert _run("rig", "fit", rec, "--sim", sim, "-o", d / "rig" / "rod1.meas.json", "--png", d / "rig" / "fig8.png",
                "--report") == 0
    assert _run("diagnose", "--rig", rec, "--sim", sim, "--json", d / "rigdiag" / "diag.json", "--png",
                d / "rigdiag", "--report") == 0
    camp = d / "camp"
    assert _run("simulate-campaign", "--rod", sim, "--fixture-error", "2:0.3,0,0", "--seed", 5, "-o", camp) == 0
    files = [camp / "multical.campaign.csv", "--fixture", camp / "multical.fixture.json"]
    val = ["--validate", camp / "multical.validation.csv"]
    assert _run("calibrate", *files, "--rod", camp / "rod.compliance.json", *val, "--json", d / "cal" / "cal.json",
                "--png", d / "cal", "--report") == 3                      # NOT TRUSTED: the wrong position
    assert _run("compare", *files, "--rod", f"fea={camp / 'rod.compliance.json'}", *val, "--json",
                d / "cmp" / "table3.json", "--png", d / "cmp" / "fig10.png", "--report") == 3   # no method trusted
    assert _run("diagnose", "--campaign", *files, "--rod", camp / "rod.compliance.json", *val, "--png", d / "dg",
                "--report") == 0                                          # no --json: rendered from memory
    assert _run("sweep", "--base", "rod1", "--L1", "250:350:100", "--L2", "700:800:100", "--serial", "-o",
                d / "sweep" / "sweep.csv", "--report") == 0
    return d


#: report page -> section titles it must show, figures it must embed
_PAGES = {
    "fea/fea.report.html": (["Compliance file"], 0),
    "calc/compliance.report.html": (["Compliance file", "2# / calc"], 0),
    "rig/rig-fit.report.html": (["Compliance file"], 1),
    "rigdiag/diagnose.report.html": (["Diagnosis"], 1),
    "cal/calibrate.report.html": (["Calibration", "NOT TRUSTED"], 2),
    "cmp/compare.report.html": (["Compensation methods compared", "nominal"], 1),
    "dg/diagnose.report.html": (["Diagnosis", "fixture_pose at position:2", "next step"], 2),
    "sweep/sweep.report.html": (["L1 x L2 sweep", "stiffest"], 1),
}


def _embedded(html: str) -> int:
    return html.count("data:image/png;base64,")


def _renders_3d() -> int:
    """1 where the 3-D views render (pyvista, off-screen OpenGL): the sweep's page then shows its base design."""
    try:
        from rodlab.core.view3d import check_offscreen
        check_offscreen()
    except Exception:
        return 0
    return 1


def test_every_command_writes_its_report(user_run):
    for rel, (must, n_figures) in _PAGES.items():
        html = (user_run / rel).read_text()
        for text in must:
            assert text in html, (rel, text)
        assert _embedded(html) == n_figures + (_renders_3d() if rel.startswith("sweep/") else 0), rel
        assert "src='http" not in html and "<script" not in html.lower(), rel
        assert "rodlab " in html and "Command:" in html


def test_folder_report_renders_every_result_once(user_run):
    assert _run("report", user_run) == 0
    html = (user_run / "report.html").read_text()
    pngs = [p for p in user_run.rglob("*.png")]
    assert _embedded(html) == len(pngs)
    titles = re.findall(r"<h2>\d+\. ([^<(]+)", html)
    for t in ("Compliance file", "L1 x L2 sweep", "Calibration", "Compensation methods compared", "Diagnosis"):
        assert any(x.strip() == t for x in titles), (t, titles)
    # the rig diagnosis (the campaign's was not written: its figures are shown at the end), and the frame, calc,
    # meas and campaign's own compliance files
    assert sum(x.strip() == "Diagnosis" for x in titles) == 1 and "<h2>Figures</h2>" in html
    assert sum(x.strip() == "Compliance file" for x in titles) == 4
    # sections in the order design -> compliance -> sweep -> calibration -> comparison -> diagnosis
    order = [x.strip() for x in titles]
    assert order.index("L1 x L2 sweep") < order.index("Calibration") < order.index("Diagnosis")


def test_compliance_tables_name_axes_and_units(user_run):
    html = (user_run / "fea" / "fea.report.html").read_text()
    for label in ("[um/N]", "[um per g0]", "force along x_T", "gravity along z_T", "ball moves along y_T"):
        assert label in html
    c = json.loads((user_run / "fea" / "rod1.compliance.json").read_text())
    assert f"{c['C_F_mm_per_N'][1][1] * 1e3:+.3f}" in html          # C_F[y, y] in um/N


def test_report_of_nothing_is_refused(tmp_path, capsys):
    assert _run("report", tmp_path) == 2
    assert "nothing to report" in capsys.readouterr().err
    f = tmp_path / "x.txt"
    f.write_text("x")
    assert _run("report", f) == 2
    assert "not a folder" in capsys.readouterr().err
    assert not (tmp_path / "report.html").exists()


def test_a_result_written_under_another_suffix_is_still_reported(tmp_path, capsys):
    """`compliance -o out.csv --report` writes its JSON under the name given; the report reads it by its content
    (the CLI fuzzing found the command exit 2 after writing out.csv: "nothing to report")."""
    out, report = tmp_path / "out.csv", tmp_path / "r.html"
    assert main(["compliance", "rod1", "-o", str(out), "--report", str(report)]) == 0
    assert json.loads(out.read_text())["format"].startswith("rodlab.compliance") and "c_rod" in report.read_text()


def test_a_report_path_that_is_a_folder_is_refused_before_any_work(tmp_path, capsys):
    """`--report DIR` (a folder) had been found only after the results were written (exit 2 with an output left)."""
    (tmp_path / "reports").mkdir()
    out = tmp_path / "rod1.compliance.json"
    assert main(["compliance", "rod1", "-o", str(out), "--report", str(tmp_path / "reports")]) == 2
    assert "--report" in capsys.readouterr().err and not out.exists()


def test_evidence_is_said_in_an_engineers_words():
    from rodlab.app.diagnose.report import Finding
    from rodlab.app.diagnose.wording import certainty, confirmation, evidence_text, explained_share
    f = Finding("friction", None, "", {"F_f_N": 0.3}, {}, 0.002, 0.001,
                {"lr_p": 1e-9, "cv_sse_before": 2.0, "cv_sse_after": 1.0})
    assert explained_share(f) == pytest.approx(0.75)
    assert evidence_text(f).startswith("explains 75 % of the residual's mean square (rms 2.00 -> 1.00 um)")
    assert certainty(f).startswith("decisive")
    weak = Finding("tare", None, "", {}, {}, 0.002, 0.0019, {"lr_p": 0.01, "cv_sse_before": 1.0, "cv_sse_after": 1.1})
    assert certainty(weak).startswith("weak") and "held-out" in certainty(weak)
    creep = Finding("creep", None, "", {}, {}, 0.002, 0.0015, {"lr_p": 3e-94, "cv_sse_before": 1.0,
                                                                "cv_sse_after": 1.1})
    assert certainty(creep).startswith("strong") and "another term may carry part of it" in certainty(creep)
    assert "2 F_f" in confirmation(f)
    fix = Finding("fixture_pose", "position:3", "", {}, {}, 0.04, 0.005, {"lr_p": 1e-20})
    assert "--free fixture_3_x" in confirmation(fix)


def test_sweep_axes_span_the_grid_only():
    from rodlab.fea.sweep_plot import grid_extent
    assert grid_extent(np.array([250.0, 350.0, 450.0])) == (200.0, 500.0)
    lo, hi = grid_extent(np.array([300.0]))
    assert lo < 300.0 < hi


def test_campaign_fits_check_their_shapes():
    from rodlab.app.diagnose.campaign import CampaignFits
    with pytest.raises(ValueError, match="q_deg"):
        CampaignFits(None, None, np.ones(3, bool), ["1.1", "1.2", "1.3"], np.ones(3, int), {}, q_deg=np.zeros((2, 6)))


def test_reports_render_in_headless_chromium(user_run, tmp_path, render_in_chromium):
    if not (user_run / "report.html").exists():
        assert _run("report", user_run) == 0
    render_in_chromium([user_run / rel for rel in _PAGES] + [user_run / "report.html"], tmp_path / "profile")
