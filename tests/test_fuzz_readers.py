"""Property-based corruption of every contract reader: a clear rodlab error naming the file, or a valid result;
never a traceback (any other exception) and never a non-finite value in a result."""
from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rodlab.core.errors import RodlabError

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "examples"

TOKENS = ["nan", "inf", "-inf", "1e308", "-1e308", "abc", "", "0", "-1", "1e-320", '"x"', "[1,2]", "true", "{}", ",,"]


def _sources():
    from rodlab.core.calc import calc_rod_compliance
    from rodlab.core.compliance import write_compliance
    from rodlab.core.design_io import builtin_designs, resolve_design
    import tempfile
    tmp = Path(tempfile.mkdtemp())
    comp = write_compliance(calc_rod_compliance(resolve_design("rod1")), tmp / "rod1.compliance.json")
    from rodlab.fea.joints import JointFit
    from rodlab.fea.joints_io import write_joints
    rng = np.random.default_rng(0)
    joints = write_joints(tmp / "rod1.joints.json", JointFit(
        resolve_design("rod1"), (25.0, 25.0), 1e-4 * rng.normal(size=(5, 6, 6)), 1e-4 * rng.normal(size=(5, 6, 3)),
        1e-6 * rng.normal(size=(2, 6))))
    out = {
        "design": (builtin_designs()["rod1"].read_bytes(), ".rod.toml"),
        "compliance": (comp.read_bytes(), ".compliance.json"),
        "joints": (joints.read_bytes(), ".joints.json"),
        "robot": ((ROOT / "calibrate" / "robots" / "tx90.toml").read_bytes(), ".toml"),
        "profile": ((ROOT / "stiffness_rig" / "plans" / "simulator.profile.toml").read_bytes(), ".toml"),
        "plan": ((ROOT / "stiffness_rig" / "plans" / "paper.plan.toml").read_bytes(), ".toml"),
    }
    out.update(_device_sources(tmp))
    mukca = ROOT / "benchmarks" / "data" / "mukca2025" / "kuka_14.sockets.csv"
    if mukca.exists():
        out["sockets"] = ("\n".join(mukca.read_text().splitlines()[:60]).encode() + b"\n", ".sockets.csv")
    if SHARED.is_dir():
        rig = (SHARED / "rig-null.rig.csv").read_text().splitlines()
        out["recording"] = ("\n".join(rig[:400]).encode() + b"\n", ".rig.csv")
        c = SHARED / "campaign-null"
        out["campaign"] = ((c / "multical.campaign.csv").read_bytes(), ".campaign.csv")
        out["fixture"] = ((c / "multical.fixture.json").read_bytes(), ".fixture.json")
        out["validation"] = ((c / "multical.validation.csv").read_bytes(), ".validation.csv")
    return out


def _device_sources(tmp: Path) -> dict:
    """A device file as built, its probe file, a raw campaign and the fixture fitted from the probes."""
    from rodlab.core.calc import calc_rod_compliance
    from rodlab.calibrate import fit_fixture, read_probe, resolve_robot, write_fixture
    from rodlab.calibrate.device import ideal_device, misaligned_device
    from rodlab.calibrate.simulate import CampaignSpec, simulate_campaign
    from rodlab.core.design_io import resolve_design
    dev = misaligned_device(ideal_device(), 2.0, np.random.default_rng(1))
    simulate_campaign(resolve_robot("tx90"), calc_rod_compliance(resolve_design("rod1")), tmp / "raw",
                      CampaignSpec(positions=3, orientations=3), device=dev)
    fix = write_fixture(fit_fixture(read_probe(tmp / "raw" / "multical.probe.csv"), dev, 1).fixture,
                        tmp / "probed.fixture.json")
    return {"device": ((tmp / "raw" / "multical.device.json").read_bytes(), ".device.json"),
            "probe": ((tmp / "raw" / "multical.probe.csv").read_bytes(), ".probe.csv"),
            "raw_campaign": ((tmp / "raw" / "multical.campaign.csv").read_bytes(), ".campaign.csv"),
            "fixture2": (fix.read_bytes(), ".fixture.json")}


SOURCES = _sources()


def _reader(kind):
    if kind == "design":
        from rodlab.core.design_io import load_design
        return load_design
    if kind == "compliance":
        from rodlab.core.compliance import read_compliance
        return read_compliance
    if kind == "joints":
        from rodlab.fea.joints_io import read_joints
        return read_joints
    if kind == "robot":
        from rodlab.calibrate.robot_formats import read_robot
        return read_robot
    if kind == "profile":
        from rodlab.stiffness_rig.config import read_profile
        return read_profile
    if kind == "plan":
        from rodlab.stiffness_rig.config import read_plan
        return read_plan
    if kind == "recording":
        from rodlab.stiffness_rig.recording import read_recording
        return read_recording
    if kind == "sockets":
        from rodlab.calibrate.sockets import read_sockets
        return lambda p: read_sockets(p, 7)
    if kind in ("device", "probe", "raw_campaign"):
        from rodlab.calibrate import read_campaign, read_device, read_probe
        from rodlab.calibrate.device import ideal_device
        return {"device": read_device, "probe": read_probe,
                "raw_campaign": lambda p: read_campaign(p, 6, ideal_device())}[kind]
    from rodlab.calibrate.campaign import read_campaign, read_fixture
    from rodlab.calibrate.points_file import read_points
    return {"campaign": read_campaign, "fixture": read_fixture, "fixture2": read_fixture,
            "validation": read_points}[kind]


@st.composite
def corruption(draw, data: bytes):
    kind = draw(st.sampled_from(["truncate", "drop_line", "dup_line", "token", "bytes", "swap_lines", "header"]))
    lines = data.split(b"\n")
    if kind == "truncate":
        return data[:draw(st.integers(0, len(data)))]
    if kind == "drop_line" and len(lines) > 1:
        i = draw(st.integers(0, len(lines) - 1))
        return b"\n".join(lines[:i] + lines[i + 1:])
    if kind == "dup_line" and lines:
        i = draw(st.integers(0, len(lines) - 1))
        return b"\n".join(lines[:i + 1] + lines[i:])
    if kind == "swap_lines" and len(lines) > 2:
        i = draw(st.integers(0, len(lines) - 2))
        lines[i], lines[i + 1] = lines[i + 1], lines[i]
        return b"\n".join(lines)
    if kind == "bytes":
        i = draw(st.integers(0, max(len(data) - 1, 0)))
        junk = draw(st.binary(min_size=1, max_size=6))
        return data[:i] + junk + data[i:]
    if kind == "header" and lines:
        i = next((k for k, l in enumerate(lines) if l and not l.startswith(b"#")), 0)
        lines[i] = lines[i].replace(b",", b",dup_,", 1) if draw(st.booleans()) else lines[i][: len(lines[i]) // 2]
        return b"\n".join(lines)
    # replace one number / value token
    text = data.decode("utf-8", "replace")
    spans = [m.span() for m in __import__("re").finditer(r"-?\d+\.?\d*(e-?\d+)?|\"[a-z_0-9#./]+\"", text)]
    if not spans:
        return data
    a, b = spans[draw(st.integers(0, len(spans) - 1))]
    return (text[:a] + draw(st.sampled_from(TOKENS)) + text[b:]).encode("utf-8")


def _finite(obj) -> bool:
    if isinstance(obj, np.ndarray):
        return obj.dtype.kind not in "fc" or bool(np.all(np.isfinite(obj)))
    if isinstance(obj, float):
        return math.isfinite(obj)
    return True


@pytest.mark.parametrize("kind", sorted(SOURCES))
def test_reader_never_crashes(kind, tmp_path):
    data, suffix = SOURCES[kind]
    reader = _reader(kind)

    @settings(max_examples=int(os.environ.get("RODLAB_FUZZ_EXAMPLES", 60)), deadline=None,
              suppress_health_check=[HealthCheck.function_scoped_fixture])
    @given(corruption(data))
    def check(bad):
        p = tmp_path / f"case{suffix}"
        p.write_bytes(bad)
        try:
            result = reader(p)
        except RodlabError as e:
            assert str(p) in str(e) or p.name in str(e), f"error does not name the file: {e}"
            return
        except Exception as e:  # noqa: BLE001
            raise AssertionError(f"{kind}: {type(e).__name__} instead of a rodlab error: {e}") from e
        for name in dir(result):
            if name.startswith("_"):
                continue
            try:
                v = getattr(result, name)
            except Exception:  # noqa: BLE001
                continue
            if isinstance(v, (np.ndarray, float)) and name not in ("time_s", "temp_C", "disp_mm", "temp"):
                assert _finite(v), f"{kind}: non-finite {name} accepted"
    check()
