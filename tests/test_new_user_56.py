"""A calibration engineer's trial with a MultiCal-like device of their own (2026-11-29, helper-56): raw readings
converted with another zero, a sensor mounted reversed, readings in um, probe files with swapped labels, in metres or
with an accuracy in um, a missing reading."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from rodlab.app.cli import main


@pytest.fixture(scope="module")
def raw(tmp_path_factory):
    """A simulated raw-reading campaign with its device and probe files."""
    out = tmp_path_factory.mktemp("raw") / "c"
    assert main(["simulate-campaign", "--rod", "rod1", "--raw", "-o", str(out)]) == 0
    return out


def _args(folder, campaign=None):
    return [str(campaign or folder / "multical.campaign.csv"), "--device", str(folder / "multical.device.json"),
            "--fixture", str(folder / "multical.fixture.json"), "--rod", str(folder / "rod.compliance.json")]


def _edited(folder, tmp_path, name, edit):
    lines = (folder / "multical.campaign.csv").read_text().splitlines()
    cols = lines[0].split(",")
    for i in range(1, len(lines)):
        cells = lines[i].split(",")
        edit(cols, cells)
        lines[i] = ",".join(cells)
    path = tmp_path / name
    path.write_text("\n".join(lines) + "\n")
    return path


def test_readings_converted_with_another_zero_are_named_device_zero(tmp_path, capsys):
    """The diagnosis had called it unexplained at one position; the offset is now found from the readings."""
    out = tmp_path / "dz"
    assert main(["simulate-campaign", "--rod", "rod1", "--effect", "device_zero:offset_mm=0.8;-0.3;0.2", "-o",
                 str(out)]) == 0
    report = tmp_path / "dz.json"
    assert main(["diagnose", "--campaign", str(out / "multical.campaign.csv"), "--fixture",
                 str(out / "multical.fixture.json"), "--rod", str(out / "rod.compliance.json"), "--json",
                 str(report)]) == 0
    findings = json.loads(report.read_text())["findings"]
    assert findings[0]["effect"] == "device_zero"
    p = findings[0]["parameters"]
    found = p["share"] * np.array([p["dx_mm"], p["dy_mm"], p["dz_mm"]])
    assert np.allclose(found, [0.8, -0.3, 0.2], atol=0.05)


def test_no_device_zero_without_a_common_offset(raw, tmp_path):
    report = tmp_path / "null.json"
    assert main(["diagnose", "--campaign", *_args(raw), "--json", str(report)]) == 0
    assert not any(f["effect"] == "device_zero" for f in json.loads(report.read_text())["findings"])


def test_a_reversed_sensor_is_named(raw, tmp_path, capsys):
    """Sensor 2 mirrored about its zero: 'unexplained' and 'check a reading column's sign or order' before."""
    zero = json.loads((raw / "multical.device.json").read_text())["sensors"][1]["zero_mm"]

    def mirror(cols, cells):
        j = cols.index("s2_mm")
        cells[j] = f"{2 * zero - float(cells[j]):.4f}"
    rev = _edited(raw, tmp_path, "rev.campaign.csv", mirror)
    capsys.readouterr()
    assert main(["calibrate", *_args(raw, rev)]) == 2
    assert "sensor 2's readings look reversed" in capsys.readouterr().err


def test_two_exchanged_sensor_columns_are_named(raw, tmp_path, capsys):
    """s1_mm and s2_mm exchanged (the channels exported in another order): named with the fix (a device trial: it had
    been read as the device file's zero, and the diagnosis as device axes 70 deg off)."""
    def exchange(cols, cells):
        a, b = cols.index("s1_mm"), cols.index("s2_mm")
        cells[a], cells[b] = cells[b], cells[a]
    swapped = _edited(raw, tmp_path, "swap.campaign.csv", exchange)
    capsys.readouterr()
    assert main(["calibrate", *_args(raw, swapped)]) == 2
    assert "the s1_mm and s2_mm columns look exchanged" in capsys.readouterr().err


@pytest.mark.parametrize("column, factor, said", [("s2_mm", 0.1, "the column is in cm; multiply it by 10"),
                                                   ("s1_mm", 1 / 25.4, "the column is in inches; multiply it by 25.4")])
def test_a_raw_column_in_cm_or_inches_is_told_its_fix(raw, tmp_path, capsys, column, factor, said):
    """A device trial: s2 in cm (1.25 against a zero of 12.5) had been named as two exchanged columns fitting to
    3.4 mm, s1 in inches as a device zero offset; each is refused naming its unit."""
    def scaled(cols, cells):
        cells[cols.index(column)] = f"{factor * float(cells[cols.index(column)]):.6f}"
    assert main(["calibrate", *_args(raw, _edited(raw, tmp_path, "unit.campaign.csv", scaled))]) == 2
    err = capsys.readouterr().err
    assert f"key `{column}`" in err and said in err and "exchanged" not in err


def test_readings_in_um_and_a_missing_reading_are_told_their_fix(raw, tmp_path, capsys):
    def in_um(cols, cells):
        for c in ("s1_mm", "s2_mm", "s3_mm"):
            cells[cols.index(c)] = f"{1000 * float(cells[cols.index(c)]):.1f}"
    assert main(["calibrate", *_args(raw, _edited(raw, tmp_path, "um.campaign.csv", in_um))]) == 2
    assert "the readings are in um; divide the s*_mm columns by 1000" in capsys.readouterr().err

    def lost(cols, cells):
        if cells[1] == "3":
            cells[cols.index("s2_mm")] = ""
    assert main(["calibrate", *_args(raw, _edited(raw, tmp_path, "lost.campaign.csv", lost))]) == 2
    assert "measure the point again, or delete its row" in capsys.readouterr().err


def _probe(raw, tmp_path, name, edit):
    lines = (raw / "multical.probe.csv").read_text().splitlines()
    path = tmp_path / name
    path.write_text("\n".join(edit(lines)) + "\n")
    world = json.loads((raw / "multical.fixture.json").read_text())["world_position"]
    return ["fixture", str(path), "--device", str(raw / "multical.device.json"), "--world-position", str(world),
            "-o", str(tmp_path / f"{name}.fixture.json")]


def test_probe_files_swapped_in_metres_or_with_an_accuracy_in_um(raw, tmp_path, capsys):
    def swap(lines):
        rows = [ln.split(",") for ln in lines]
        i2 = next(i for i, r in enumerate(rows) if r[:2] == ["2", "ball_2"])
        i3 = next(i for i, r in enumerate(rows) if r[:2] == ["2", "ball_3"])
        rows[i2][1], rows[i3][1] = "ball_3", "ball_2"
        return [",".join(r) for r in rows]
    assert main(_probe(raw, tmp_path, "swap.probe.csv", swap)) == 3
    err = capsys.readouterr().err
    assert "are swapped" in err and "ball_2" in err and "ball_3" in err

    def metres(lines):
        out = []
        for ln in lines:
            r = ln.split(",")
            out.append(",".join(r[:2] + [f"{float(v) / 1000:.7f}" for v in r[2:]]) if r[0].isdigit() else ln)
        return out
    assert main(_probe(raw, tmp_path, "m.probe.csv", metres)) == 2
    assert "in metres: multiply x_mm, y_mm, z_mm by 1000" in capsys.readouterr().err
    assert main(_probe(raw, tmp_path, "acc.probe.csv", lambda ls: ["# accuracy_mm: 5"] + ls[1:])) == 2
    assert "if it is in um, write 0.005" in capsys.readouterr().err
    assert main(_probe(raw, tmp_path, "noacc.probe.csv", lambda ls: ["# accuracy_mm: "] + ls[1:])) == 2
    err = capsys.readouterr().err                     # not a reading: not 'the sensor lost the ball' (review)
    assert "accuracy_mm" in err and "lost the ball" not in err


def test_a_device_file_in_metres_is_named_not_the_probe_file(raw, tmp_path, capsys):
    """The device file's features in metres, the probe file right: the device file and its key are named (review:
    the probe file had been called 'in um')."""
    data = json.loads((raw / "multical.device.json").read_text())
    data["features_D_mm"] = {k: [v / 1000 for v in xyz] for k, xyz in data["features_D_mm"].items()}
    device = tmp_path / "m.device.json"
    device.write_text(json.dumps(data, indent=1))
    args = _probe(raw, tmp_path, "ok.probe.csv", lambda ls: ls)
    args[args.index("--device") + 1] = str(device)
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "m.device.json" in err and "features_D_mm" in err and "metres" in err and "probe.csv" not in err


def test_misalign_without_raw_readings_is_refused(tmp_path, capsys):
    assert main(["simulate-campaign", "--rod", "rod1", "--misalign-deg", "2", "-o", str(tmp_path / "x")]) == 2
    assert "give --raw with it" in capsys.readouterr().err and not (tmp_path / "x").exists()


def test_the_same_two_labels_swapped_everywhere_names_the_device_file(raw, tmp_path, capsys):
    """ball_2 and ball_3 exchanged at every position: the summary names the device file's two features, and no
    fixture is written from exchanged labels (review: 'accuracy_mm may be the repeatability' and a fixture 90 mm
    wrong)."""
    def swap_all(lines):
        out = []
        for ln in lines:
            r = ln.split(",")
            if len(r) > 1 and r[1] in ("ball_2", "ball_3"):
                r[1] = "ball_3" if r[1] == "ball_2" else "ball_2"
            out.append(",".join(r))
        return out
    args = _probe(raw, tmp_path, "swapall.probe.csv", swap_all)
    assert main(args) == 3
    err = capsys.readouterr().err
    assert "the same two labels swap everywhere" in err and "'ball_2' and 'ball_3'" in err
    assert "repeatability" not in err and "not written" in err
    assert not Path(args[args.index("-o") + 1]).exists()


@pytest.mark.parametrize("seed", [1, 2])
def test_device_zero_offered_on_an_honest_soft_rod_is_not_chosen(tmp_path, seed):
    """The legacy rod 1# is soft enough for the device's springs to push its ball ~0.2 mm off the aligned point,
    so with 96 points the readings' mean passes the offer rule: the hypothesis is offered on an honest campaign
    and must not be found (review: the null test above never offered it)."""
    from conftest import legacy_design
    from rodlab import calc_rod_compliance
    from rodlab.app.diagnose import diagnose_campaign
    from rodlab.calibrate import read_campaign, read_fixture, read_points, resolve_robot
    from rodlab.calibrate.effects.device_zero import readings_offset
    from rodlab.calibrate.simulate import CampaignSpec, simulate_campaign
    robot, rod = resolve_robot("tx90"), calc_rod_compliance(legacy_design("rod1"))
    simulate_campaign(robot, rod, tmp_path, CampaignSpec(seed=seed, positions=8, orientations=12), effects={})
    camp = read_campaign(tmp_path / "multical.campaign.csv")
    assert readings_offset(camp.x_D_mm) is not None                      # offered
    diag = diagnose_campaign(robot, camp, read_fixture(tmp_path / "multical.fixture.json"), rod,
                             validate_points=read_points(tmp_path / "multical.validation.csv"))[0]
    assert not any(f.effect == "device_zero" for f in diag.findings)


def test_validate_pairs_a_probe_file_with_its_device_file(raw, tmp_path, capsys):
    """`rodlab validate DEV.device.json PROBE.csv` checks the probe file as `rodlab fixture` would fit it: a
    feature the device lacks (at its line), two swapped labels, a device file in metres; an honest pair passes."""
    device = str(raw / "multical.device.json")
    assert main(["validate", device, str(raw / "multical.probe.csv")]) == 0

    def typo(lines):
        return [ln.replace(",ball_1,", ",ball_9,", 1) if ln.startswith("3,ball_1,") else ln for ln in lines]
    bad = _probe(raw, tmp_path, "typo.probe.csv", typo)[1]
    capsys.readouterr()
    assert main(["validate", device, bad]) == 2
    err = capsys.readouterr().err
    assert "line" in err and "'ball_9' is not in the device file's features_D_mm" in err and "ball_1" in err

    def swap(lines):
        out = []
        for ln in lines:
            r = ln.split(",")
            if r[0] == "2" and r[1] in ("ball_2", "ball_3"):
                r[1] = "ball_3" if r[1] == "ball_2" else "ball_2"
            out.append(",".join(r))
        return out
    assert main(["validate", device, _probe(raw, tmp_path, "swap.probe.csv", swap)[1]]) == 2
    assert "are swapped" in capsys.readouterr().err

    data = json.loads((raw / "multical.device.json").read_text())
    data["features_D_mm"] = {k: [v / 1000 for v in xyz] for k, xyz in data["features_D_mm"].items()}
    metres = tmp_path / "m.device.json"
    metres.write_text(json.dumps(data, indent=1))
    assert main(["validate", str(metres), str(raw / "multical.probe.csv")]) == 2
    assert "m.device.json" in capsys.readouterr().err


def test_simulated_raw_readings_through_the_users_own_device(tmp_path, capsys):
    """simulate-campaign --raw --device: dial gauges of 10 mm stroke zeroed near 5 mm, two sensors off
    orthogonal, other springs and features; the readings lie about its zeros, the files are its, and rodlab
    calibrate reads them through it to a trusted fit (the device trial: only the built-in device had been
    simulated). --device without --raw is refused."""
    s2, s3 = np.array([0.0349, 0.99939, 0.0]), np.array([0.0, -0.0262, 0.99966])
    dev = {"format": "rodlab.device/1", "name": "lab-dev", "sensors": [
        {"axis_D": [1.0, 0.0, 0.0], "zero_mm": 5.0, "range_mm": [0.0, 10.0], "force_at_zero_N": 0.6,
         "rate_N_per_mm": 0.08},
        {"axis_D": (s2 / np.linalg.norm(s2)).tolist(), "zero_mm": 5.2, "range_mm": [0.0, 10.0],
         "force_at_zero_N": 0.7, "rate_N_per_mm": 0.08},
        {"axis_D": (s3 / np.linalg.norm(s3)).tolist(), "zero_mm": 4.9, "range_mm": [0.0, 10.0],
         "force_at_zero_N": 0.65, "rate_N_per_mm": 0.08}],
        "features_D_mm": {"a": [30.0, 0.0, -50.0], "b": [-15.0, 26.0, -50.0], "c": [-15.0, -26.0, -50.0],
                          "d": [0.0, 0.0, -35.0]}}
    path = tmp_path / "lab.device.json"
    path.write_text(json.dumps(dev))
    out = tmp_path / "c"
    assert main(["simulate-campaign", "--rod", "rod1", "--raw", "--device", str(path), "-o", str(out)]) == 0
    written = json.loads((out / "multical.device.json").read_text())
    assert written["name"] == "lab-dev" and set(written["features_D_mm"]) == {"a", "b", "c", "d"}
    cols = (out / "multical.campaign.csv").read_text().splitlines()[0].split(",")
    rows = np.array([[float(v) for v in ln.split(",")[cols.index("s1_mm"):cols.index("s3_mm") + 1]]
                     for ln in (out / "multical.campaign.csv").read_text().splitlines()[1:]])
    assert np.all(np.abs(rows - [5.0, 5.2, 4.9]).max(axis=0) < 2.0)       # about its zeros, inside its strokes
    capsys.readouterr()
    assert main(["calibrate", *_args(out), "--validate", str(out / "multical.validation.csv")]) == 0
    assert "verdict: TRUSTED" in capsys.readouterr().out
    assert main(["simulate-campaign", "--rod", "rod1", "--device", str(path), "-o", str(tmp_path / "x")]) == 2
    assert "give --raw with it" in capsys.readouterr().err


def test_a_sensor_that_reads_the_other_way_is_declared_in_the_device_file(raw, tmp_path, capsys):
    """Sensor 2 reading the other way (mounted round, or its channel counting down): the campaign's mirrored s2
    column calibrates through a device file that declares sensors[2].reading_sign -1 (rodlab.device/2) as the
    original does through its own file (the device trials: it could only be turned round or the column rewritten);
    the refusal without it names the declaration; the file round-trips."""
    from rodlab.calibrate.device import DEVICE_FORMAT_SIGNED, read_device, write_device
    doc = json.loads((raw / "multical.device.json").read_text())
    zero = doc["sensors"][1]["zero_mm"]

    def mirror(cols, cells):
        j = cols.index("s2_mm")
        cells[j] = f"{2 * zero - float(cells[j]):.4f}"
    rev = _edited(raw, tmp_path, "rev.campaign.csv", mirror)
    doc["format"], doc["sensors"][1]["reading_sign"] = DEVICE_FORMAT_SIGNED, -1
    signed = tmp_path / "signed.device.json"
    signed.write_text(json.dumps(doc))
    dev = read_device(signed)
    assert list(dev.signs) == [1, -1, 1]
    x = np.array([[0.3, -0.2, 0.1], [-1.0, 0.5, 2.0]])
    assert np.allclose(dev.positions(dev.readings(x)), x)
    again = read_device(write_device(dev, tmp_path / "again.device.json"))
    assert json.loads((tmp_path / "again.device.json").read_text())["format"] == DEVICE_FORMAT_SIGNED
    assert list(again.signs) == [1, -1, 1]
    capsys.readouterr()
    args = [str(rev), "--device", str(signed), "--fixture", str(raw / "multical.fixture.json"), "--rod",
            str(raw / "rod.compliance.json"), "--json", str(tmp_path / "signed.json")]
    assert main(["calibrate", *args]) == 0
    assert main(["calibrate", *_args(raw), "--json", str(tmp_path / "plain.json")]) == 0
    a, b = (json.loads((tmp_path / f"{n}.json").read_text())["parameters"] for n in ("signed", "plain"))
    assert all(abs(a[k]["value"] - b[k]["value"]) < 1e-6 * max(1.0, abs(b[k]["value"])) for k in b)
    capsys.readouterr()
    assert main(["calibrate", *_args(raw, rev)]) == 2
    assert "sensors[2].reading_sign: -1" in capsys.readouterr().err
    assert main(["validate", str(signed)]) == 0
    doc["format"] = "rodlab.device/1"                  # the sign in a /1 file: told its format, not "remove it"
    (tmp_path / "v1.device.json").write_text(json.dumps(doc))
    capsys.readouterr()
    assert main(["validate", str(tmp_path / "v1.device.json")]) == 2
    assert 'belongs to rodlab.device/2: change the file\'s format to "rodlab.device/2"' in capsys.readouterr().err
    assert main(["validate", str(raw / "truth.json")]) == 0              # the simulator's own record
