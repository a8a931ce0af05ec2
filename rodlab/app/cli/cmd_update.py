"""``rodlab update``: the rod as built, by fitting a design's uncertain keys to a measured compliance."""
from __future__ import annotations

import argparse
import re
from pathlib import Path

import numpy as np


from ...core.calc import calc_rod_compliance
from ...core.compliance import read_compliance
from ...core.design_io import resolve_design
from ...core.enums import Method
from ...core.errors import DesignError, RodlabError, VerdictError, did_you_mean
from ...core.fileio import read_text_checked
from ...core.joint_springs import JOINT_PLACES
from ...core.sensitivity import MODULI, with_values
from ...core.tolerances import design_tolerances, design_value
from ...core.units import PAPER_R_ROD
from .rodargs import warn_rod_mismatch
from .update_measured import measured_entries_of

__all__ = ["register"]

def register(sub) -> None:
    p = sub.add_parser("update", help="fit a design's uncertain keys to a measured compliance (the rod as built)",
                       description="Model updating: fit the freed dotted keys of DESIGN (bounded, priors from its "
                                   "[tolerances] and the documented defaults) so that the compliance model "
                                   "reproduces the measured C_F; write the as-built design (your file with the "
                                   "fitted values, the design's in comments); print each key with its uncertainty, "
                                   "the correlations, the keys the measurement cannot separate (and which load, "
                                   "gauge or measurement would), and r_mn before and after.")
    p.add_argument("design", help="*.rod.toml design or a built-in name (rod1 ... rod6)")
    p.add_argument("--measured", required=True,
                   help="a measured *.compliance.json (rodlab rig fit) or a *.rig.csv recording (diagnosed first: "
                        "friction, creep, drift ... are separated from the linear compliance)")
    p.add_argument("--free", default=None, metavar="KEY[,KEY...]",
                   help="dotted keys of the design file to fit (default: E_GPa and G_GPa of the tube material, and "
                        "where they cannot explain the measurement, moduli); moduli: every modulus of every material "
                        "times one factor (a rod uniformly softer than its design, as the paper's r_rod 1.01-2.30); a "
                        f"joint's compliance joints.PLACE.s_bend_rad_per_Nm (PLACE: {', '.join(JOINT_PLACES)}) "
                        "declares it in the as-built design (rodlab.rod/2)")
    p.add_argument("--model", choices=("frame", "calc"), default="frame",
                   help="compliance model the keys are fitted through (default: the calibrated frame, ~1 %% of the "
                        "solid FEA; calc: the closed form, 6-17 %% stiffer on average, up to ~25 %% in an entry)")
    p.add_argument("--sim", default=None, metavar="SIM.compliance.json",
                   help="your own simulated compliance of the design (another code's FEA, a solid run): fitted "
                        "through it, moved by the frame's sensitivities to the keys (C_sim x frame(as built) / "
                        "frame(design)), with its method's accuracy, instead of through --model; the recording is "
                        "diagnosed against it too")
    p.add_argument("--accept-unexplained", action="store_true",
                   help="write the as-built design from a recording whose hold means the diagnosis leaves partly "
                        "unexplained (refused by default: the linear compliance fitted beside such structure may "
                        "carry part of it; its uncertainties are widened by the lack of fit)")
    p.add_argument("-o", "--output", required=True, help="the as-built design to write (*.rod.toml)")
    p.set_defaults(func=cmd_update)


def _default_free(design) -> list[str]:
    m = design.pipe_I.material
    keys = [f"materials.{m.name}.E_GPa"]
    if m.G_GPa is not None:
        keys.append(f"materials.{m.name}.G_GPa")
    return keys


def _closed_form_hint(args, design) -> str:
    """Where the recording was made by ``rodlab rig simulate`` (whose ``--sim DESIGN`` is the design's closed form)
    and the closed form differs from the model fitted through by more than 3 % on a diagonal entry: say so (a
    trial's shear-soft carbon rod with a titanium bend: c33 26 % apart, the unchanged design refused)."""
    if args.model == "calc" or args.sim or not str(args.measured).endswith(".rig.csv"):
        return ""
    head = Path(args.measured).read_text(encoding="utf-8", errors="replace")[:2000]
    if "# generator: rodlab rig simulate" not in head:
        return ""
    sim = re.search(r"^# sim: (.*)$", head, re.MULTILINE)       # rodlab's since session 45: the truth it simulated
    if sim and not sim.group(1).rstrip().endswith("(calc)"):
        return ""                                           # not the closed form (a trial: the user's own model)
    from ..update import model_compliance
    calc, model = np.diag(calc_rod_compliance(design).C_F), np.diag(model_compliance(args.model)(design))
    apart = np.abs(calc / model - 1.0)
    k = int(np.argmax(apart))
    if apart[k] <= 0.03:
        return ""
    said = (f"with --sim {sim.group(1).strip()}, the design's closed form" if sim else
            f"if with --sim {args.design}, that is the design's closed form")
    return (f". The recording was made by `rodlab rig simulate`: {said}, which differs from the {args.model} model "
            f"by {100 * apart[k]:.0f} % in c{k + 1}{k + 1} on this design: simulate from `rodlab fea {args.design} "
            f"--model {args.model} -o SIM.json` (--sim SIM.json) to "
            f"test update on its own model (--model calc would not fit it either: it removes the closed form's known "
            f"stiffness against the solid FEA, which the recording keeps)")


#: the rod's lengths: geometry a caliper or the calibration's tool vector measures, not the compliance
LENGTH_KEYS = ("L1_mm", "L2_mm")


def _lengths_note(res) -> None:
    """A freed length (L1, L2) moves the ball and so every tool vector: fitted from the compliance it takes up
    what other keys differ by (a paper-rod trial: L2 533 +- 1.9 mm for 529, a thinner wall read as a longer rod,
    the tool point 8 mm off, without a word)."""
    for k, v0, v, s in zip(res.keys, res.nominal, res.x, res.sigma):
        if k in LENGTH_KEYS:
            print(f"  note: {k} was fitted from the compliance ({v0:g} -> {v:.4g} +- {s:.2g} mm): a length moves the "
                  "ball, and a compliance fit lets it take up what other keys differ by (a thinner wall reads as a "
                  f"longer tube); measure {k} with a caliper or take the ball from the calibration's identified tool "
                  "vector, and fit the walls and moduli with it held")


def cmd_update(args: argparse.Namespace) -> int:
    from ...core.design_edit import write_edited_design
    from ..update import ROUGH_P, as_built_values, update_design
    try:
        found = Path(args.measured).is_file()
    except OSError as e:                                 # a name the file system refuses (too long, ...)
        raise RodlabError(f"--measured {args.measured}: {e.strerror or e}; give the measured file's path") from e
    if not found:
        raise RodlabError(f"--measured {args.measured}: no such file (give a measured *.compliance.json from `rodlab rig "
                          "fit` or a *.rig.csv recording)")
    design = resolve_design(args.design)
    keys = [k.strip() for k in args.free.split(",") if k.strip()] if args.free else _default_free(design)
    if design.source is None:
        raise RodlabError("the design has no file to start from: give a *.rod.toml or a built-in name")
    if Path(args.output).resolve() == Path(design.source).resolve():
        raise RodlabError(f"-o {args.output} is the design itself: the as-built design goes beside it (e.g. "
                          f"{Path(design.source).name.replace('.rod.toml', '')}.asbuilt.rod.toml), so that the design "
                          "as drawn is not lost")
    for key in keys:                                   # a misspelt key is named before the recording is diagnosed
        _check_key(design, key)
        _check_moves(design, key, "frame" if args.sim else args.model)
    own = _own_sim(args, design)
    measured, causes = measured_entries_of(args.measured, design, keys, args.model, own, args.accept_unexplained)
    if causes:
        print("the recording also shows: " + ", ".join(causes) + " (rig effects, separated from the linear "
              "compliance; see `rodlab diagnose --rig`)")
    res = update_design(design, measured, keys, args.model, own)
    if res.p_after < ROUGH_P and not args.free:        # the tube's moduli fit roughly or not: uniformly softer?
        res = _uniformly(design, measured, res, args.model, own)
    _print(res, _through(args))
    _held_note(res, design)
    if not res.explains:
        _refuse(args, res)
    text = read_text_checked(design.source, DesignError)
    header = (f"# as built: rodlab update {args.design} --measured {args.measured} --free {','.join(res.keys)} "
              + (f"--sim {args.sim}\n" if args.sim else f"--model {args.model}\n"))
    out = write_edited_design(text, design, as_built_values(design, res.keys, res.x), args.output, header)
    print(f"wrote {out}")
    return 0


def _check_key(design, key: str) -> None:
    """A key of the design, or :data:`~rodlab.core.sensitivity.MODULI`; a misspelt ``moduli`` is told so."""
    if key == MODULI:
        return
    try:
        design_value(design, key)
    except DesignError as e:
        hint = did_you_mean(key, [MODULI])
        if hint:
            raise RodlabError(f"--free {key}: no such key of design {design.name!r}.{hint} (every modulus of the rod "
                              "by one factor)") from e
        raise


def _check_moves(design, key: str, model: str) -> None:
    """Refuse a key the compliance model does not depend on (a trial: ``materials.X.nu`` of a material giving its
    own G_GPa had been fitted, then refused as unexplained): 5 % of it changes no C_F entry by 1e-9."""
    if key == MODULI or key.startswith("joints."):
        return
    from ..update import model_compliance
    fn = model_compliance(model)
    value = design_value(design, key)
    C0, moved = fn(design), 0.0
    for step in (1.001, 0.999):                      # a small step either way: a value at its rule's edge
        try:
            C1 = fn(with_values(design, {key: value * step if value else step - 1.0}))
        except DesignError:
            continue
        moved = max(moved, float(np.max(np.abs(C1 - C0))))
    if moved <= 1e-12 * np.max(np.abs(C0)):
        raise RodlabError(f"--free {key}: the {model} model's compliance does not depend on it (e.g. a Poisson's ratio "
                          f"where the material gives its own G_GPa, a density): free a key that moves the rod's "
                          f"compliance (`rodlab diagnose --rig` lists the keys the recording resolves)")


def _own_sim(args, design):
    """``--sim``: the user's simulated compliance of the design, or None; a file of another rod is refused."""
    if args.sim is None:
        return None
    sim = read_compliance(args.sim)
    if sim.method is Method.MEAS:
        raise RodlabError(f"--sim {args.sim} is a measured compliance (method meas): --sim is what the design was "
                          f"simulated as; give the measurement with --measured")
    warn_rod_mismatch(sim.rod, design.name, args.sim, "--sim", "the design")
    return sim


#: the chi-square drop by which one factor of every modulus replaces a rough fit of the tube's E and G
CLEARLY_BETTER_CHI2 = 6.0


def _uniformly(design, measured, res, model: str, own=None):
    """The default keys (the tube's E and G) explain the measurement roughly or not at all: every modulus by one
    factor (:data:`~rodlab.core.sensitivity.MODULI`) where that explains it (and, against a rough fit, within the
    noise and better by :data:`CLEARLY_BETTER_CHI2` with a key fewer: two fits alike keep the tube's), with a note;
    else the first result. (A paper trial: 3#, r_rod 2.30, with a steel bend;
    a blind trial: creep and friction on a rod 1.24x its simulation, where E and G passed at p = 1.2e-3, chi-square
    13.4 and c33 4 % off, against 1.76 for one factor of every modulus.)"""
    from ..update import ROUGH_P, update_design
    uniform = update_design(design, measured, (MODULI,), model, own)
    if not uniform.explains:
        return res
    if res.explains and (uniform.p_after < ROUGH_P or res.chi2_after - uniform.chi2_after < CLEARLY_BETTER_CHI2):
        return res                   # a rough fit of the tube's moduli stays unless one factor fits clearly better
    how = "cannot explain the measurement" if not res.explains else "explain the measurement only roughly"
    print(f"note: {', '.join(res.keys)} alone {how} (chi-square {res.chi2_after:.3g} after their "
          f"fit, p = {res.p_after:.1e}; {uniform.chi2_after:.3g} with one factor of every modulus, p = "
          f"{uniform.p_after:.1e}): the other members differ by the same factor; fitted instead: every modulus of "
          f"every material by one factor (--free {MODULI}; give --free to choose the keys yourself)")
    return uniform


def _through(args) -> str:
    """What the keys were fitted through, as the output says it."""
    return (f"{args.sim} (your simulation, moved by the frame's sensitivities to the keys)" if args.sim else
            f"the {args.model} model")


def _refuse(args, res) -> None:
    recording = args.measured if args.measured.endswith(".rig.csv") else (
        read_compliance(args.measured).provenance.get("recording") or "RECORDING.rig.csv (the file's own recording)")
    design = resolve_design(args.design)
    raise VerdictError(f"{args.measured}: {', '.join(res.keys)} cannot explain the measurement (chi-square "
                       f"{res.chi2_after:.3g} on {len(res.entries)} entries after the fit through "
                       f"{_through(args)}, p = {res.p_after:.1e}): the rod differs in a way these keys cannot move"
                       + (f" (or {args.sim} itself is off by more than its method's accuracy)" if args.sim else "")
                       + ". `rodlab "
                       f"diagnose --rig {recording} --design {args.design}` weighs every toleranced key at once: "
                       "where it names a local cause, free that cause's key (a joint's "
                       "joints.PLACE.s_bend_rad_per_Nm); where it finds every member uniformly softer "
                       f"(compliance_scale), free {MODULI}, and where it lists causes the data fit about as well "
                       "with (a joint beside a scale: y and z series alone cannot tell them apart), free theirs in "
                       "turn; where it calls the rod consistent (model_form), free the "
                       "keys its finding lists as resolved together with these, or the tube's sizes (tube.wall_mm, "
                       "tube.outer_diameter_mm); nothing was written" + _closed_form_hint(args, design))


def _print(res, through: str) -> None:
    print(f"fitted through {through}: chi-square of the {len(res.entries)} entries "
          f"{res.chi2_before:.2f} -> {res.chi2_after:.2f}")
    if res.sigma_scale > 1.0:
        print(f"  note: the freed keys fit the entries only roughly (p = {res.p_after:.1e} after the fit): their "
              f"uncertainties are widened x{res.sigma_scale:.2f} (the Birge ratio); freeing the key that carries the "
              "rest (`rodlab diagnose --rig` lists the resolved keys) would fit better")
    print(f"  {'key':34s} {'design':>10s} {'as built':>10s} {'+-':>9s}")
    for k, v0, v, s in zip(res.keys, res.nominal, res.x, res.sigma):
        change = f"({(v / v0 - 1):+.1%})" if v0 else "(the design has it rigid)"
        print(f"  {k:34s} {v0:10.4g} {v:10.4g} {s:9.2g}  {change}")
    if len(res.keys) > 1:
        print("  correlations: " + "; ".join(f"{a} / {b} {res.corr[i, j]:+.2f}" for i, a in enumerate(res.keys)
                                           for j, b in enumerate(res.keys) if j > i))
    for a, b, c, how in res.inseparable:
        print(f"  the measurement cannot separate {a} from {b} (together they move the measured entries alike, "
              f"multiple correlation {c:.3f}; the priors split them): to separate them, {how}")
    for k, change, sd in res.beyond_tolerance(2.0):
        sd = abs(sd)
        if abs(change) > 3.0 * sd:
            print(f"  note: {k} moved {change:+.1%}, more than 3x its tolerance ({sd:.1%}): the part is not what the "
                  "design says (another material or lay-up, a units slip, the wrong rod's data), or keys left fixed "
                  "carry part of the difference within their own tolerances (free them too, e.g. tube.wall_mm and "
                  "tube.outer_diameter_mm, as `rodlab diagnose --rig` weighs them all); check it before using the "
                  "as-built design")
        else:               # 2-3 tolerances: possible, and as likely a key left fixed (a trial: a thinner wall)
            print(f"  note: {k} moved {change:+.1%}, {abs(change) / sd:.1f}x its tolerance ({sd:.1%}): unusual for "
                  "one key; keys left fixed may carry part of it within their own tolerances (a wall 0.2 mm thinner "
                  "reads as a lower E): `rodlab diagnose --rig` weighs every toleranced key at once, and weighing the "
                  "rod or measuring the wall tells them apart")
    _moduli_note(res)
    _lengths_note(res)
    names = [f"r_{m + 1}{n + 1}" for m, n in res.entries]
    print(f"  r_mn = measured / the prediction of {through}, its known bias against the solid FEA removed "
          f"(`rig fit` divides by the simulated file as it is):")
    print("  r_mn before: " + ", ".join(f"{n} {r:.4f}" for n, r in zip(names, res.r_before)))
    print("  r_mn after:  " + ", ".join(f"{n} {r:.4f}" for n, r in zip(names, res.r_after)))


def _held_note(res, design) -> None:
    """The design's toleranced keys this fit held at their design values: the freed keys' +- assumes them exact, and
    what they would carry within their tolerances the freed keys carry instead (a trial: E 93.7 +- 0.8 GPa for a
    truth of 99, a thinner wall and a softer bond in it; `diagnose --rig` weighs every key: 96.9 [89.8, 105])."""
    held = [p for p in design_tolerances(design) if p.key not in res.keys and not p.key.startswith("joints.")]
    if not held or MODULI in res.keys:
        return
    shown = ", ".join(f"{p.key} {p.relative:.1%}" for p in held[:6]) + (f" and {len(held) - 6} more"
                                                                          if len(held) > 6 else "")
    print(f"  note: the +- holds the design's other toleranced keys at their design values ({shown}); within their "
          f"tolerances they may carry part of the change the freed keys carry here: `rodlab diagnose --rig` weighs "
          f"them all at once (its interval is the wider, honest one), --free adds them where the recording resolves "
          f"them")


def _moduli_note(res) -> None:
    """Every modulus freed: what its factor says of the rod (1 / factor is the r_rod it carries), against the
    paper's measured rods."""
    if MODULI not in res.keys:
        return
    r = 1.0 / float(res.x[list(res.keys).index(MODULI)])
    where = ("within" if PAPER_R_ROD[0] - 0.05 <= r <= PAPER_R_ROD[1] + 0.05 else "outside")
    print(f"  note: every modulus x{1 / r:.3f}: the rod as built is {r:.2f}x as compliant as its design throughout "
          f"(r_rod {r:.2f}; {where} the paper's measured rods, {PAPER_R_ROD[0]:.2f}-{PAPER_R_ROD[1]:.2f}); the "
          "as-built file scales every material's E and G, including the bend's, rings' and holders'")
