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


def _named(diag) -> list[str]:
    return [f.effect.value if hasattr(f.effect, "value") else str(f.effect) for f in diag.findings]


def score(expected: list[str], named: list[str], verdict: str) -> str:
    """``right``, ``wrong`` (a vocabulary effect named that no expectation allows) or ``missed``."""
    allowed = {a.split("@")[0] for e in expected for a in e.split("|")}
    hard = [n for n in named if n not in SOFT]
    if any(n not in allowed for n in hard):
        return "wrong"
    for e in expected:
        options = {a.split("@")[0] for a in e.split("|")}
        if options & SOFT and (not hard or options & set(hard)):
            continue
        if not options & set(named) and not (options & {"consistent"} and verdict == "consistent"):
            return "missed"
    return "right"


def main() -> int:
    rows, tally = [], {m: {"right": 0, "wrong": 0, "missed": 0} for m in ("design", "exact")}
    with tempfile.TemporaryDirectory() as tmp:
        sims = {}
        for name in ("rod1", "rod4"):
            sims[name] = calc_rod_compliance(resolve_design(name))
            write_compliance(sims[name], Path(tmp) / f"{name}.compliance.json")
        subprocess.run([sys.executable, str(HERE / "rig_independent_sim.py"), "--out", str(Path(tmp) / "recs")],
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
                cells.append(f"{verdict}: {', '.join(named) or '-'} (**{result}**)")
            rows.append("| " + " | ".join(cells) + " |")
    n = len(rows)
    lines = ["# Blind benchmark: rig recordings of an independent simulator", "",
             "`python benchmarks/rig_independent.py`: " + str(n) + " recordings of rods 1# (carbon) and 4# (steel) by "
             "`benchmarks/rig_independent_sim.py`, a simulator written from the contract alone (its own schedules, "
             "friction, creep, tilt, gauge and drift forms); diagnosed against the designs' closed form with the "
             "design's envelope (the default of `rodlab diagnose --rig`) and told the simulation is exact.", "",
             "| case | expected | default (design envelope) | `--sim-accuracy exact` |", "|---|---|---|---|", *rows, "",
             "| | right | wrong cause | missed |", "|---|---:|---:|---:|"]
    for mode, label in (("design", "default"), ("exact", "exact")):
        t = tally[mode]
        lines.append(f"| {label} | {t['right']}/{n} | {t['wrong']}/{n} | {t['missed']}/{n} |")
    write_page(OUT, lines, HERE / "rig_independent_notes.md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
