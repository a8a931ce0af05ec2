"""`rodlab study rod1 .. rod6 --robot tx90 --robot-floor-mm 0.263` (linear predictor, the default rod slip)
against the paper's Table 3 and its findings (Section 5.3)."""
from __future__ import annotations

import pytest

#: Table 3 mean positioning error after calibration [mm]: rod -> method -> mean
TABLE3_MEAN_MM = {"1#": {"none": 0.302, "fea": 0.276, "meas": 0.274}, "2#": {"none": 0.312, "fea": 0.290, "meas": 0.286},
                  "3#": {"none": 0.414, "fea": 0.364, "meas": 0.362}, "4#": {"none": 0.475, "fea": 0.450, "meas": 0.451},
                  "5#": {"none": 0.392, "fea": 0.372, "meas": 0.371}, "6#": {"none": 0.601, "fea": 0.505, "meas": 0.507}}
METHODS = ("none", "fea", "meas")


@pytest.fixture(scope="module")
def predicted(tmp_path_factory):
    """{rod: {method: predicted mean [mm]}} of the command."""
    import pandas as pd

    from rodlab.app.cli.main import main
    out = tmp_path_factory.mktemp("paper") / "s"
    rc = main(["study", "rod1", "rod2", "rod3", "rod4", "rod5", "rod6", "--robot", "tx90", "--robot-floor-mm", "0.263",
               "--methods", ",".join(METHODS), "--serial", "-q", "-o", str(out)])
    assert rc == 0
    df = pd.read_csv(out / "study.csv")
    return {r: {m: float(df[(df.design == r) & (df.method == m)].mean_mm.iloc[0]) for m in METHODS}
            for r in TABLE3_MEAN_MM}


@pytest.mark.parametrize("rod", sorted(TABLE3_MEAN_MM))
def test_means_within_25_percent_of_table3(predicted, rod):
    for m in METHODS:
        assert predicted[rod][m] == pytest.approx(TABLE3_MEAN_MM[rod][m], rel=0.25), (rod, m)


@pytest.mark.parametrize("carbon, steel", [("1#", "4#"), ("2#", "5#"), ("3#", "6#")])
def test_each_carbon_rod_beats_its_steel_twin_with_every_method(predicted, carbon, steel):
    for m in METHODS:
        assert predicted[carbon][m] < predicted[steel][m], m


def test_long_rods_are_the_worst_of_their_material(predicted):
    for m in METHODS:
        assert predicted["3#"][m] > max(predicted["1#"][m], predicted["2#"][m])
        assert predicted["6#"][m] > max(predicted["4#"][m], predicted["5#"][m])


def test_compensation_gains_most_on_the_long_soft_rod(predicted):
    gain = {r: predicted[r]["none"] - min(predicted[r]["fea"], predicted[r]["meas"]) for r in predicted}
    assert gain["6#"] == max(gain.values())
    assert min(gain[r] for r in ("4#", "5#", "6#")) > max(gain[r] for r in ("1#", "2#"))
