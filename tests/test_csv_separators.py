"""A CSV written with semicolons (a spreadsheet in a decimal-comma locale) or tabs: every reader and `rodlab validate`
say so and how to fix it, instead of naming the whole header line as one unknown column."""
from __future__ import annotations

import pytest

from rodlab.app.cli import main
from rodlab.calibrate import CalibrationError
from rodlab.calibrate.campaign import read_campaign
from rodlab.calibrate.points_file import read_points
from rodlab.core.schema import check_file

HEADER = "q1,q2,q3,q4,q5,q6,position,x_mm,y_mm,z_mm"
ROW = "10,20,30,40,50,60,0,100.5,200.25,300.125"


@pytest.mark.parametrize("sep,name", [(";", "semicolons"), ("\t", "tabs")])
def test_campaign_and_validation_files_with_another_separator(tmp_path, sep, name, capsys):
    for reader, fname in ((read_campaign, "c.campaign.csv"), (read_points, "v.validation.csv")):
        path = tmp_path / fname
        comment = "# tool_mm: 0, 0, 300\n" if reader is read_points else ""
        path.write_text(comment + "\n".join(line.replace(",", sep).replace(".", "," if sep == ";" else ".")
                                             for line in (HEADER, ROW)) + "\n")
        with pytest.raises(CalibrationError, match=f"line {1 + bool(comment)}: the header is separated by {name}, not commas"):
            reader(path)
    check = check_file(tmp_path / "c.campaign.csv")
    assert [p.message for p in check.problems] == [f"the header is separated by {name}, not commas"]
    assert main(["validate", str(tmp_path / "c.campaign.csv")]) != 0
    assert "export the file again as CSV with ','" in capsys.readouterr().err
