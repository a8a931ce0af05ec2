"""Score the rig diagnosis on recordings another simulator made (``rig_independent_sim.py``: its own load
schedules, friction that lets go at mass 0 and scatters from hold to hold, Kelvin-Voigt creep of one or two
terms, a tilted load, gauge gain errors, a flange spring, warm-up drift, a load cell), the only rodlab input being
the designs' closed-form C_F. Each recording is diagnosed as `rodlab diagnose --rig REC --sim DESIGN` does (the
design's envelope) and with ``--sim-accuracy exact`` (the simulator's truth *is* the closed form).

    python benchmarks/rig_independent.py        # writes docs/benchmarks/rig_independent.md

Scored per case against the simulator's expectation: right (every expected effect named, no other vocabulary
effect; ``a|b`` accepts either, ``model_form`` and ``unexplained`` accept an honest answer), a wrong cause (an
effect named that is not there), or missed.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from pages import write_page

from rodlab import calc_rod_compliance, resolve_design
from rodlab.app.diagnose import diagnose_rig
from rodlab.core.compliance import write_compliance
from rodlab.stiffness_rig import read_recording

HERE = Path(__file__).resolve().parent
OUT = HERE.parent / "docs" / "benchmarks" / "rig_independent.md"
SOFT = {"model_form", "unexplained", "consistent"}


def _named(diag) -> list[tuple[str, str]]:
    return [(f.effect.value if hasattr(f.effect, "value") else str(f.effect), f.location or "") for f in diag.findings]


def score(expected: list[str], findings: list[tuple[str, str]], verdict: str) -> str:
    """``right``, ``wrong`` (a vocabulary effect named that no expectation allows, or at another place than the
    expected one) or ``missed``; ``findings``: (effect, location) named."""
    allowed = {}
    for e in expected:
        for a in e.split("|"):
            effect, _, place = a.partition("@")
            allowed.setdefault(effect, set()).add(place)
    named = [f for f, _ in findings]
    hard = [(f, loc) for f, loc in findings if f not in SOFT]
    for f, loc in hard:
        places = allowed.get(f)
        if places is None or ("" not in places and not places & set((loc or "").split("|"))):
            return "wrong"
    for e in expected:
        options = {a.split("@")[0] for a in e.split("|")}
        if options & SOFT and (not hard or options & {f for f, _ in hard}):
            continue
        if not options & set(named) and not (options & {"consistent"} and verdict == "consistent"):
            return "missed"
    return "right"


#: the case list's own seeds (the development set the diagnosis was fixed on) and a held-out draw of every case
SETS = {"development": 0, "held out": 1000}


def main() -> int:
    lines = ["# Blind benchmark: rig recordings of an independent simulator", "",
             "`python benchmarks/rig_independent.py`: the recordings of rods 1# (carbon) and 4# (steel) by "
             "`benchmarks/rig_independent_sim.py`, a simulator written from the contract alone (its own schedules, "
             "friction, creep, tilt, gauge and drift forms); diagnosed against the designs' closed form with the "
             "design's envelope (the default of `rodlab diagnose --rig`) and told the simulation is exact. The "
             "development set (the case list's seeds) is the one the diagnosis was fixed on; the held-out set draws "
             "every case again with other seeds (`--seed-offset 1000`: other noise, friction scatter and tilt "
             "directions). A joint counts as right at its place only.", ""]
    for label, offset in SETS.items():
        lines += _run_set(label, offset)
    write_page(OUT, lines, HERE / "rig_independent_notes.md")
    return 0


def _run_set(label: str, offset: int) -> list[str]:
    rows, tally = [], {m: {"right": 0, "wrong": 0, "missed": 0} for m in ("design", "exact")}
    with tempfile.TemporaryDirectory() as tmp:
        sims = {}
        for name in ("rod1", "rod4"):
            sims[name] = calc_rod_compliance(resolve_design(name))
            write_compliance(sims[name], Path(tmp) / f"{name}.compliance.json")
        subprocess.run([sys.executable, str(HERE / "rig_independent_sim.py"), "--out", str(Path(tmp) / "recs"),
                        "--seed-offset", str(offset)],
                       check=True, capture_output=True, env=dict(os.environ, RIG_INDEPENDENT_DIR=tmp))
        for truth_path in sorted((Path(tmp) / "recs").glob("*.truth.json")):
            truth = json.loads(truth_path.read_text())
            rec = read_recording(truth_path.with_name(truth["name"] + ".rig.csv"))
            design, sim = resolve_design(truth["design"]), sims[truth["design"]]
            cells = [truth["name"], " + ".join(truth["expected"])]
            for mode, accuracy in (("design", None), ("exact", "exact")):
                diag, _ = diagnose_rig(rec, sim, design, accuracy=accuracy)
                verdict = diag.verdict.value if hasattr(diag.verdict, "value") else str(diag.verdict)
                named = _named(diag)
                result = score(truth["expected"], named, verdict)
                tally[mode][result] += 1
                text = ", ".join(f + (f" at {loc}" if loc and f == "joint_compliance" else "") for f, loc in named)
                cells.append(f"{verdict}: {text or '-'} (**{result}**)")
            rows.append("| " + " | ".join(cells) + " |")
    n = len(rows)
    out = [f"## {label.capitalize()} set", "", "| case | expected | default (design envelope) | `--sim-accuracy exact` |",
           "|---|---|---|---|", *rows, "", "| | right | wrong cause | missed |", "|---|---:|---:|---:|"]
    for mode, name in (("design", "default"), ("exact", "exact")):
        t = tally[mode]
        out.append(f"| {name} | {t['right']}/{n} | {t['wrong']}/{n} | {t['missed']}/{n} |")
    print(label, {m: dict(t) for m, t in tally.items()}, flush=True)
    return out + [""]

if __name__ == "__main__":
    sys.exit(main())
