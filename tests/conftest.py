"""Shared fixtures: the contract examples in ../shared and a design-dict factory."""
from __future__ import annotations

import copy
import os
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared"
EXAMPLES = SHARED / "examples"
ROD1 = ROOT / "rodlab" / "data" / "rods" / "rod1.rod.toml"

# Under pytest-xdist (`-n auto`, the README's test command; see pytest_xdist_auto_num_workers below) each worker's
# BLAS, MKL (PARDISO) and OpenMP keep to one thread, or the workers' threads outnumber the cores many times over
# (measured on 2 cores with two workers: 13 % more wall time and 20 % more CPU time for the FEA, mix-up and spread
# tests). Set before NumPy or MKL is loaded (the CLI's subprocesses inherit it); a value the user set is kept. The
# variables are rodlab.core.cluster.ONE_THREAD_ENV's (a Dask worker's), written out: importing rodlab loads NumPy.
if os.environ.get("PYTEST_XDIST_WORKER"):
    for _var in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OMP_NUM_THREADS"):
        os.environ.setdefault(_var, "1")


#: the most workers ``-n auto`` starts (each may run gmsh, VTK, Chromium or a Dask cluster: ~1 GB at most)
MAX_AUTO_WORKERS = 8


@pytest.hookimpl(optionalhook=True)                     # pytest without xdist (-p no:xdist) runs as before
def pytest_xdist_auto_num_workers(config):
    """``-n auto``: one worker more than the cores this process may run on, at most :data:`MAX_AUTO_WORKERS`;
    xdist's ``PYTEST_XDIST_AUTO_NUM_WORKERS`` overrides it. The rig's tests wait for their simulators in real time
    (~230 s of the suite's ~1160 s run one after the other), and the extra worker computes meanwhile (2 cores: 8:29
    with three workers, 9:58 with two, in one hour's runs). The multithreaded paths (PARDISO and OpenBLAS on every
    core, a Dask cluster beside a multithreaded main process) run in a bare ``python -m pytest``, not under xdist."""
    override = os.environ.get("PYTEST_XDIST_AUTO_NUM_WORKERS", "").strip()
    if override:
        return int(override)
    from rodlab.core.cores import usable_cores          # here, not above: the workers' variables come first
    return min(usable_cores() + 1, MAX_AUTO_WORKERS)


@pytest.fixture(scope="session", autouse=True)
def _mesh_cache_of_the_session(tmp_path_factory):
    """The tests' meshes are cached in a folder of this session, never in the user's ~/.cache (and subprocesses
    inherit it)."""
    before = os.environ.get("RODLAB_CACHE_DIR")
    os.environ["RODLAB_CACHE_DIR"] = str(tmp_path_factory.mktemp("rodlab-cache"))
    yield
    if before is None:
        os.environ.pop("RODLAB_CACHE_DIR", None)
    else:
        os.environ["RODLAB_CACHE_DIR"] = before


def legacy_dict(name: str) -> dict:
    """The rodlab.rod/1 table of built-in rod ``name`` as it was before issue #45 (frozen in
    fea/data/reference_designs.json with the solid-FEA references computed on it): the subject of tests about
    machinery (rig, diagnosis, joints, model updating) whose numbers were set on that design, not of tests about
    the paper's rods."""
    from rodlab.fea.reference_designs import reference_spec
    return dict({"format": "rodlab.rod/1"}, **reference_spec(name))


def legacy_design(name: str):
    """Built-in rod ``name`` as it was before issue #45 (see :func:`legacy_dict`)."""
    from rodlab.fea.reference_designs import reference_design
    return reference_design(name)


def legacy_file(path: Path, name: str) -> Path:
    """Write :func:`legacy_dict` of ``name`` as a design file at ``path``."""
    return write_toml(path, legacy_dict(name))


def diagnose_simulated(folder: Path, robot, rod):
    """The campaign diagnosis of a simulated campaign folder (``multical.*`` files) with its validation points."""
    from rodlab.app.diagnose import diagnose_campaign
    from rodlab.calibrate import read_campaign, read_fixture, read_points
    return diagnose_campaign(robot, read_campaign(folder / "multical.campaign.csv"),
                             read_fixture(folder / "multical.fixture.json"), rod,
                             validate_points=read_points(folder / "multical.validation.csv"))[0]


def rewrite_recording(src: Path, dst: Path, edit=None, meta=None, prefix: str = "") -> Path:
    """A copy of the rig recording ``src`` at ``dst``: ``edit(i, row)`` changes data row ``i`` in place (``row``: column
    -> cell text), ``meta(line)`` returns each comment line as it should be, ``prefix`` goes before the first byte
    (a byte-order mark). Recordings of another rig, a units slip or a glitch are made this way from a simulated one."""
    lines = Path(src).read_text().splitlines()
    head = next(i for i, s in enumerate(lines) if not s.startswith("#"))
    cols = lines[head].split(",")
    out = [meta(line) if meta else line for line in lines[:head]] + [lines[head]]
    for i, line in enumerate(lines[head + 1:]):
        row = dict(zip(cols, line.split(",")))
        if edit:
            edit(i, row)
        out.append(",".join(row[c] for c in cols))
    Path(dst).write_text(prefix + "\n".join(out) + "\n", encoding="utf-8")
    return Path(dst)


@pytest.fixture
def examples() -> Path:
    if not EXAMPLES.is_dir():
        pytest.skip("../shared/examples is not present beside the repository")
    return EXAMPLES


@pytest.fixture(scope="session")
def tx90():
    """The built-in TX90 robot model."""
    from rodlab.calibrate import resolve_robot
    return resolve_robot("tx90")


@pytest.fixture(scope="session")
def rod1_calc():
    """Rod 1#'s closed-form compliance file (read-only)."""
    from rodlab import calc_rod_compliance, resolve_design
    return calc_rod_compliance(resolve_design("rod1"))


@pytest.fixture
def rod1_dict() -> dict:
    """Parsed rod 1# design as it was before issue #45 (:func:`legacy_dict`), to be modified by a test."""
    return copy.deepcopy(legacy_dict("rod1"))


def write_toml(path: Path, data: dict) -> Path:
    """Minimal TOML writer for test designs (tables of scalars, one level of nesting)."""
    lines = []
    scalars = {k: v for k, v in data.items() if not isinstance(v, dict)}
    tables = {k: v for k, v in data.items() if isinstance(v, dict)}

    def fmt(v):
        if isinstance(v, str):
            return f'"{v}"'
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, float) and v != v:
            return "nan"
        if isinstance(v, float) and v in (float("inf"), float("-inf")):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    for k, v in scalars.items():
        lines.append(f"{k} = {fmt(v)}")
    for name, tbl in tables.items():
        sub = {k: v for k, v in tbl.items() if isinstance(v, dict)}
        flat = {k: v for k, v in tbl.items() if not isinstance(v, dict)}
        if flat or not sub:
            lines.append(f"[{name}]")
            lines.extend(f"{k} = {fmt(v)}" for k, v in flat.items())
        for sname, stbl in sub.items():
            lines.append(f"[{name}.{sname}]")
            lines.extend(f"{k} = {fmt(v)}" for k, v in stbl.items())
    path.write_text("\n".join(lines) + "\n")
    return path


def _chromium():
    chromium = shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")
    driver = shutil.which("chromedriver")
    if not (chromium and driver):
        if os.environ.get("CI"):
            pytest.fail("Chromium and chromedriver are needed in CI to render the reports (.ci/run installs the "
                        "Debian packages chromium chromium-driver)")
        pytest.skip("chromium / chromedriver not installed (Debian packages chromium chromium-driver)")
    try:
        from selenium import webdriver  # noqa: F401
    except ImportError:
        if os.environ.get("CI"):
            pytest.fail("selenium is needed in CI (the test extra installs it)")
        pytest.skip("selenium not installed (pip install -e .[test])")
    return chromium, driver


def _render_in_chromium(pages: list, profile) -> None:
    """Open each page in headless Chromium: every image decodes (naturalWidth > 100) and the console has no
    error. Shared by the demo's report test."""
    chromium, driver_bin = _chromium()
    from selenium import webdriver
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service
    opts = Options()
    opts.binary_location = chromium
    for a in ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
              "--disable-background-networking", "--disable-component-update", "--disable-sync",
              f"--user-data-dir={profile}"):
        opts.add_argument(a)
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    drv = webdriver.Chrome(service=Service(driver_bin), options=opts)
    try:
        for page in pages:
            drv.get(page.resolve().as_uri())
            imgs = drv.execute_script("return Array.from(document.images).map(i => [i.complete, i.naturalWidth])")
            assert all(ok and w > 100 for ok, w in imgs), (page, imgs)
            severe = [e for e in drv.get_log("browser") if e["level"] == "SEVERE"]
            assert not severe, (page, severe)
            assert drv.find_element("tag name", "h1").text.startswith("rodlab")
    finally:
        drv.quit()


@pytest.fixture
def render_in_chromium():
    """``render_in_chromium(pages, profile_dir)``: open each HTML page in headless Chromium and check it; in CI a
    missing Chromium fails instead of skipping."""
    return _render_in_chromium


@pytest.fixture(scope="session")
def rod4_plan():
    """(robot, fixture, planned joint angles per clamping position [rad], calc compliance) of the steel rod 4# on
    the TX90: the study and rod-slip tests' shared campaign."""
    import numpy as np

    from rodlab.calibrate import Rod, resolve_robot
    from rodlab.calibrate.plan import plan_poses
    from rodlab.calibrate.simulate import standard_fixture
    from rodlab.core.calc import calc_rod_compliance
    from rodlab.core.design_io import resolve_design
    robot = resolve_robot("tx90")
    fixture = standard_fixture()
    d = resolve_design("rod4")
    rod = calc_rod_compliance(d)
    q, _ = plan_poses(robot, fixture, Rod.rigid(d.tool_mm, rod.mass_kg, rod.com_T_mm))
    return robot, fixture, {j: np.deg2rad(v) for j, v in q.items()}, rod


def linear_and_monte_carlo(rod4_plan, priors, replicates: int = 12) -> tuple[dict, dict]:
    """The linear predictor (256 draws) and Monte Carlo (``replicates``, no error budget) on the rod 4# campaign
    for the methods none and fea: ({method: linear summary}, {method: Monte-Carlo accuracy})."""
    from rodlab.calibrate.predict import predict_accuracy
    from rodlab.calibrate.predict_linear import predict_linear
    from rodlab.calibrate.simulate import standard_base
    robot, fixture, plan, rod = rod4_plan
    mc = {a.method: a for a in predict_accuracy(robot, plan, fixture, standard_base(), rod, None, ["none", "fea"],
                                                priors, replicates=replicates, seed=0, budget=False)}
    lin = {a.method: a for a in predict_linear(robot, plan, fixture, standard_base(), rod, None, ["none", "fea"],
                                               priors, draws=256).summaries}
    return lin, mc
