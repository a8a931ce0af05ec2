"""The main job end to end: rodlab demo, run.json, the HTML report (checked in headless Chromium)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from rodlab.app.pipeline import STAGES, run_demo
from rodlab.app.report import write_folder_report as write_report


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo")
    run_demo(out, seed=3, sweep_grid=(np.array([150.0, 300.0, 450.0]), np.array([300.0, 450.0, 600.0])))
    return out


def test_demo_stages_and_results(run):
    s = json.loads((run / "run.json").read_text())
    st = s["stages"]
    assert list(st) == list(s["timings_s"]) == STAGES
    if "skipped" not in st["cad"]:           # built in a second process: the design's parts and mass, four views
        assert st["cad"]["parts"] == 8 and st["cad"]["mass_kg"] == pytest.approx(st["design"]["mass_kg"], rel=1e-6)
        assert [(run / p).stat().st_size > 10_000 for p in s["files"]["cad_views"]] == [True] * 4
    d = st["diagnose"]
    assert d["verdict"] == "explained"           # the rod as built against its design: the rig's friction, the bond
    assert {(f["effect"], f["location"]) for f in d["findings"]} == {("friction", None), ("joint_compliance", "ring_1")}
    assert d["corrected_vs_true_max_rel"] < 0.01
    up, truth = d["update"], st["rig"]["as_built"]    # the update recovers the drawn laminate and the bond
    for key, value in truth.items():
        i = up["keys"].index(key)
        assert abs(up["as_built"][i] - value) < 3 * up["sigma"][i] + 0.01 * value, key
    assert (run / "rod1.asbuilt.rod.toml").exists()
    t3 = st["calibrate"]["table3"]
    assert set(t3) == {"nominal", "None", "Calc", "FEA", "Meas", "Corrected"}
    assert t3["FEA"]["mean_mm"] < t3["None"]["mean_mm"] < t3["nominal"]["mean_mm"]
    for rel in ("rod1.fea.compliance.json", "rod1.meas.compliance.json", "rod1.corrected.compliance.json",
                "rig/rod1.rig.csv", "campaign/multical.campaign.csv", "sweep/sweep.csv", st["fea"]["fields"],
                "study/recommended.vtp"):
        assert (run / rel).exists(), rel
    if st["fea"]["model"] == "solid":   # the sweep's frame is joint-calibrated on that solid run: rod 1#'s row agrees
        import pandas as pd
        assert st["sweep"]["frame_calibration"]["joints_of"] == "1#"
        df = pd.read_csv(run / "sweep" / "sweep.csv")
        row = df[(df["L1_mm"] == 300.0) & (df["L2_mm"] == 450.0)].iloc[0]
        assert row["c_rod_um"] == pytest.approx(st["fea"]["c_rod_um"], rel=0.002)
        # its mesh was made in the background, the plan and the analysis beside it (rodlab.app.solid_mesher)
        prov = json.loads((run / "rod1.fea.compliance.json").read_text())["provenance"]
        assert prov["timings_s"]["ahead_beside_mesher"] > 0


def test_demo_study_of_the_carbon_rods(run):
    """The demo's study: every rod is predicted more accurate with measured compensation than without, and
    compensation gains most on the softest rod (3#), as the paper's Section 5.3 finds."""
    sy = json.loads((run / "run.json").read_text())["stages"]["study"]
    assert sy["designs"] == ["1#", "2#", "3#"]
    mean = {(r["design"], r["method"]): r["mean_mm"] for r in sy["rows"]}
    assert len(mean) == 12
    for d in sy["designs"]:
        assert mean[(d, "meas")] < mean[(d, "none")]
        assert mean[(d, "meas")] <= mean[(d, "fea")]
    assert mean[("3#", "none")] - mean[("3#", "meas")] > mean[("1#", "none")] - mean[("1#", "meas")]
    assert sy["recommendation"].startswith("build ")
    assert (run / "study" / "study.html").exists() and (run / "study" / "study.csv").exists()


def test_report_is_self_contained(run):
    html = write_report(run).read_text()
    n_files = sum(1 for v in json.loads((run / "run.json").read_text())["files"].values()
                  for _ in (v if isinstance(v, list) else [v]))
    assert html.count("data:image/png;base64,") == n_files
    assert "src='http" not in html and "<script" not in html.lower()


def test_report_in_headless_chromium(run, render_in_chromium):
    render_in_chromium([write_report(run)], run / "chrome-profile")     # written here: tests may run in any order


def _page_text(page: str) -> str:
    import html
    import re
    page = re.sub(r"<(style|title)>.*?</\1>", " ", page, flags=re.S)
    page = re.sub(r"<img[^>]*>", " ", page)
    return re.sub(r"\s+", " ", html.unescape(re.sub(r"<[^>]+>", " ", page)))


def test_report_tells_one_story(run):
    """The conclusion comes first (what to build, what accuracy, with what compensation); sections 6 and 8 say
    which rod each assumes (exactly as its file / as built with r_rod drawn); c_rod, r_rod and {T} are explained
    where they first appear."""
    import re
    s = json.loads((run / "run.json").read_text())["stages"]
    page = write_report(run).read_text()
    assert re.findall(r"<h2>([^<]*)</h2>", page)[:2] == ["Conclusion", "Terms"]
    text = _page_text(page)
    sy, rec = s["study"], s["study"]["recommended"]
    row = next(r for r in sy["rows"] if r["design"] == rec["design"] and r["method"] == rec["method"])
    conclusion = _page_text(page[page.index("<h2>Conclusion</h2>"):page.index("<h2>Terms</h2>")])
    assert f"Build {rec['design']}" in conclusion and f"{row['mean_mm']:.3f} mm" in conclusion
    assert "with Meas compensation" in conclusion and "section 6" in conclusion and "section 8" in conclusion
    sec6 = text[text.index("6. Calibration"):text.index("7. L1 / L2 sweep")]
    sec8 = text[text.index("8. Which rod?"):]
    assert "Rod assumed: the rod as built of sections 4-5" in sec6
    assert f"true r_rod = {s['campaign']['r_rod_true']:.3f}" in sec6
    lo, hi = sy["r_prior"]["1#"]
    assert "Rod assumed: as built" in sec8 and f"r_rod drawn from {lo:g}-{hi:g}" in sec8
    rod1_calc = next(r["mean_mm"] for r in sy["rows"] if r["design"] == "1#" and r["method"] == "calc")
    assert f"{rod1_calc:.3f} mm here against {s['calibrate']['table3']['Calc']['mean_mm']:.3f} mm" in sec8
    for term, meaning in (("c_rod", "compliance index"), ("r_rod", "correction factor"), ("{T}", "tool frame")):
        first = text.index(term)
        assert meaning in text[first:first + 80], (term, text[first - 100:first + 100])


def test_demo_study_is_rodlab_study_with_its_defaults(run, tmp_path):
    """A user who reruns the demo's study from the command line gets the demo's numbers and choice: the same
    priors (the rod slip included), the same family's joint calibration."""
    from rodlab.app.cli import main
    assert main(["study", "rod1", "rod2", "rod3", "--robot", "tx90", "-o", str(tmp_path / "st"), "-q"]) == 0
    cli = json.loads((tmp_path / "st" / "study.json").read_text())
    sy = json.loads((run / "run.json").read_text())["stages"]["study"]
    assert cli["recommendation"]["design"] == sy["recommended"]["design"]
    import pandas as pd
    df = pd.read_csv(tmp_path / "st" / "study.csv").dropna(subset=["method"])
    got = {(r.design, r.method): r.mean_mm for r in df.itertuples()}
    for r in sy["rows"]:
        assert got[(r["design"], r["method"])] == pytest.approx(r["mean_mm"], rel=0.01), (r["design"], r["method"])
