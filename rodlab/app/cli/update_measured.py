"""``rodlab update --measured``: the measured entries from a measured compliance file or a diagnosed recording,
and the recording's checks before an as-built design is fitted to it (structural causes the freed keys cannot
carry, structure the diagnosis leaves unexplained)."""
from __future__ import annotations

import sys

import numpy as np

from rodlab.stiffness_rig import read_recording

from ...core.calc import calc_rod_compliance
from ...core.compliance import RodCompliance, read_compliance
from ...core.errors import RodlabError, VerdictError
from ...core.sensitivity import MODULI, MODULUS_KEYS, STRUCTURAL_ENTRIES
from .recording_checks import check_recording
from .rodargs import warn_rod_mismatch

__all__ = ["measured_entries_of"]

#: causes a rig diagnosis names in the linear compliance itself (not design keys)
_STRUCTURAL = ("joint_compliance", "torsion_compliance", "compliance_scale")


def _explained_by_keys(finding, keys, design, alternatives: bool = True) -> bool:
    """Whether a structural finding is what the freed ``keys`` fit: a joint freed at its place (or at one of the
    places a group names, ``pipe_II|ring_1``), a compliance scale with the tubes' modulus E or the moduli freed, a
    torsion of pipe I with its material's shear modulus G freed; or one of the causes the data fit about as well
    with (a designer trial's y and z series: a bond named as a scale, the bond's key freed, refused)."""
    others = _alternative_causes(finding) if alternatives else []
    return any(_cause_freed(effect, location, keys, design) for effect, location in [(finding.effect, finding.location)]
               + others)


def _cause_freed(effect: str, location: str | None, keys, design) -> bool:
    """Whether the freed ``keys`` fit the cause ``effect`` at ``location`` (see :func:`_explained_by_keys`)."""
    if effect == "joint_compliance":
        freed = {k.split(".")[1] for k in keys if k.startswith("joints.")}
        return bool(set((location or "").split("|")) & freed)
    if effect == "compliance_scale":
        wanted = {f"materials.{t.material.name}.E_GPa" for t in (design.pipe_I, design.pipe_II)} | {MODULI}
    elif effect == "torsion_compliance":
        wanted = {f"materials.{design.pipe_I.material.name}.G_GPa"}
    else:
        return False
    return bool(wanted & set(keys))


def _check_unexplained(path: str, diag, accept: bool) -> None:
    """A recording the diagnosis leaves partly unexplained. Structure left in the hold means (a lack of fit no
    effect explains: their reduced chi-square above the diagnosis's ``LACK_CHI_RED``) may be carried by the linear
    compliance fitted beside it: refused unless ``accept`` (two trials: an as-built file had been written beside it
    with a warning only); what the diagnosis modelled or left out (a slip, a glitch, a stray hold, a gauge at its
    stop, correlated readings within the holds) a warning."""
    from ..diagnose.rig_steps import LACK_CHI_RED
    left = [f for f in diag.findings if f.effect == "unexplained"]
    lack = [f for f in left if float(f.parameters.get("reduced_chi2", 0.0)) > LACK_CHI_RED]
    if lack and not accept:
        where = ", ".join(dict.fromkeys(f.location or "?" for f in lack))
        chi = max(float(f.parameters["reduced_chi2"]) for f in lack)
        raise VerdictError(f"{path}: the diagnosis leaves structure in the hold means unexplained (at {where}; reduced "
                           f"chi-square {chi:.1f}): the linear compliance fitted beside it may carry part of it, so no "
                           "as-built design is written; find its cause with `rodlab diagnose --rig` (re-record the "
                           "holds it names), or give --accept-unexplained to write it anyway (its uncertainties "
                           "widened by the lack of fit)")
    if left:
        where = ", ".join(dict.fromkeys(f.location or "?" for f in left))
        print(f"warning: {path}: the diagnosis leaves part of the recording unexplained (at {where}); the linear "
              "compliance fitted here may carry some of it: see `rodlab diagnose --rig` before using the as-built "
              "design", file=sys.stderr)


def measured_entries_of(path: str, design, keys, model: str, own=None, accept_unexplained: bool = False):
    """The measured entries from a compliance file or, for a recording, its diagnosed linear part (against the
    ``model`` the keys are fitted through, or the user's own simulation ``own``)."""
    from ..update import Measured, model_compliance
    if path.endswith(".rig.csv"):
        from ..diagnose import diagnose_rig
        C = model_compliance(model)(design)
        sim = own or RodCompliance.from_design(design, C, calc_rod_compliance(design).C_g,
                                               "fea" if model == "frame" else "calc", {"model": model})
        rec = read_recording(path)
        other_rod = warn_rod_mismatch(rec.rod, design.name, path, "--measured", "the design")
        check_recording(rec, sim, override=None)
        diag, fitted = diagnose_rig(rec, sim, design)
        rig = [f.effect for f in diag.findings if f.effect not in ("model_form", "unexplained", *_STRUCTURAL)]
        unfitted = [f for f in diag.findings if f.effect in _STRUCTURAL and not _explained_by_keys(f, keys, design)]
        strictly = [f for f in diag.findings if f.effect in _STRUCTURAL
                    and not _explained_by_keys(f, keys, design, alternatives=False)]
        if strictly and other_rod:
            raise RodlabError(f"{path}: the recording is of rod {rec.rod!r}, the design of rod {design.name!r}, and "
                              "they differ beyond the design's tolerances: a measurement of another rod cannot make "
                              "this rod's as-built design; give this rod's recording (or its design)")
        _refuse_unfitted(path, unfitted, design, "simulation you gave (--sim)" if own else f"{model} model", keys)
        for f in diag.findings:               # e.g. a joint at the flange clamp: maybe the rig's mount
            if f.effect in _STRUCTURAL and f.evidence.get("caution"):
                print(f"warning: {path}: {f.effect} at {f.location}: {f.evidence['caution']}", file=sys.stderr)
        lin = fitted.linear
        _check_unexplained(path, diag, accept_unexplained)
        return Measured(lin.entries, lin.C, _with_remounting(lin.C, lin.cov), path), rig
    comp = read_compliance(path)
    warn_rod_mismatch(comp.rod, design.name, path, "--measured", "the design", named_by="")
    E = _measured_entries(comp, path)
    C = np.array([comp.C_F[e] for e in E])
    stated = np.zeros(len(E)) if comp.C_F_sigma is None else np.array([comp.C_F_sigma[e] for e in E])
    return Measured(E, C, _with_remounting(C, np.diag(stated ** 2)), path), []


def _measured_entries(comp: RodCompliance, path: str) -> tuple:
    """The structural entries a compliance file measured: nonzero ones, and where the file states uncertainties
    (``rig fit``'s), only those with one: an entry without (a series the recording lacks, completed as r_rod x the
    simulation) was never measured and is left out, with a note (a technician trial: an interrupted run's c11 had
    been fitted as if measured)."""
    E = [e for e in STRUCTURAL_ENTRIES if abs(comp.C_F[e]) > 1e-9 * np.abs(comp.C_F).max()]
    if comp.C_F_sigma is None:
        return tuple(E)
    left = [e for e in E if not np.isfinite(comp.C_F_sigma[e])]
    if left:
        print(f"note: {path}: {', '.join(f'c{m + 1}{n + 1}' for m, n in left)} not measured (no uncertainty in the "
              "file: completed from the simulation as r_rod x simulated); left out of the fit")
    kept = tuple(e for e in E if e not in left)
    if not kept:
        raise RodlabError(f"--measured {path}: no C_F entry of the file was measured (C_F_sigma_mm_per_N is null "
                          "everywhere); give rig fit's measured file of this rod")
    return kept


def _with_remounting(C: np.ndarray, cov: np.ndarray) -> np.ndarray:
    """The covariance ``cov`` [(mm/N)^2] of measured entries ``C`` [mm/N] (a recording's fit, a file's stated
    errors) with what one mounting of the rod adds: remounting and refitting repeat each entry to
    :data:`~rodlab.app.diagnose.envelope.MEAS_RELATIVE` (1 %)."""
    from ..diagnose.envelope import MEAS_RELATIVE
    return cov + np.diag((MEAS_RELATIVE * np.abs(C)) ** 2)


def _keys_for(finding, design) -> list[str]:
    """The design keys that would fit a structural finding: a joint's bending compliance at its (first) place and,
    where the finding has a torsion that its interval keeps off 0, its torsional one (a CalculiX trial: without it
    the tube's G had carried a bond's torsion, -54 %); every modulus (:data:`~rodlab.app.update.MODULI`) for a
    uniform scale; pipe I's shear modulus G for a torsion."""
    if finding.effect == "joint_compliance":
        place = (finding.location or "PLACE").split("|")[0]
        lo = (finding.intervals.get("s_torsion_rad_per_Nm") or (0.0, 0.0))[0]
        torsion = [f"joints.{place}.s_torsion_rad_per_Nm"] if lo > 0 else []
        return [f"joints.{place}.s_bend_rad_per_Nm", *torsion]
    if finding.effect == "compliance_scale":
        return [MODULI]
    return [f"materials.{design.pipe_I.material.name}.G_GPa"]


def _refuse_unfitted(path: str, findings: list, design, model: str, freed: list) -> None:
    """Refuse a recording whose diagnosis names structural causes the ``freed`` keys cannot fit, with what each
    one is and the keys to free (those freed and the one that would fit it)."""
    if not findings:
        return
    what = {"joint_compliance": "a local cause (a bond, clamp or thread)",
            "compliance_scale": "every member uniformly softer or stiffer (another laminate or material, a units slip)",
            "torsion_compliance": "pipe I softer in torsion (its shear modulus or lay-up)"}
    named = "; ".join(f"{f.effect}" + (f" at {f.location}" if f.location else "") + f": {what[f.effect]}"
                      for f in findings)
    wanted = [k for f in findings for k in _keys_for(f, design)]
    if MODULI in wanted:                                 # moduli scales the freed materials' moduli too
        freed = [k for k in freed if not (k.startswith("materials.") and k.rpartition(".")[2] in MODULUS_KEYS)]
    keys = ",".join(dict.fromkeys([*freed, *wanted]))   # the keys freed, plus
    raise VerdictError(f"{path}: diagnosed against the {model} of {design.name} (what update fits "
                      f"through), the recording shows {named}; beyond the design's tolerances and not a key freed "
                      f"here. Free the key that fits it too (--free {keys})"
                      + (", or repair or re-bond the joint and measure again" if "joints." in keys else "")
                      + _alternatives(findings, freed)
                      + " (`rodlab diagnose --rig` shows the findings)")


def _alternatives(findings: list, freed: list) -> str:
    """The --free lists of the joints the data fit about as well as a named cause (a designer trial's y and z
    series: a bond named as a uniform scale, whose moduli were then refused, while the bond's key fitted)."""
    places = list(dict.fromkeys(place for f in findings for effect, place in _alternative_causes(f)
                                if effect == "joint_compliance" and place))[:2]
    if not places:
        return ""
    other = [",".join(dict.fromkeys([*freed, *(f"joints.{p}.s_{kind}_rad_per_Nm" for kind in ("bend", "torsion"))]))
             for p in places]
    apart = " (a load series along x tells them apart)" if any(f.evidence.get("separate_by") for f in findings) else ""
    return (f"; the data fit about as well with a joint at {' or '.join(places)}{apart}: try "
            + " or ".join(f"--free {o}" for o in other))


def _alternative_causes(finding) -> list[tuple[str, str | None]]:
    """(effect, first place) of each cause a finding's diagnosis says the data fit about as well with (its
    ``alternatives`` labels, 'EFFECT at PLACE[|PLACE] (settings)')."""
    out = []
    for label in getattr(finding, "evidence", {}).get("alternatives", ()):
        effect, _, place = label.split(" (")[0].partition(" at ")
        out.append((effect.strip(), place.split("|")[0].strip() or None))
    return out


