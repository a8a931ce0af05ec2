"""Which of the hypotheses at one place of a campaign goes first, and what a finding cannot rule out.

One joint's angle error has competing forms (a periodic error once or twice per revolution, backlash, a spring
that stiffens with the torque): they are forms of one place, not parts (:func:`same_place`). Where the best form is
one the data do not pin down (a periodic error of a joint that turned less than one period fits any smooth error of
that joint) and a rival form at its place fits as well, the rival goes first (:func:`resolved_first`): an
independent simulator's torque-stiffened joint 2 had been named a twice-per-revolution error that tied it to 0.1
in delta BIC, and the validation was worse with it (0.061 / 0.320 mm mean / max against 0.039 / 0.101). A
finding lists the effects and forms at its place that fit within delta BIC 10 (:func:`rival_forms`).
"""
from __future__ import annotations

from rodlab.core.hypothesis import Hypothesis

from .criteria import DBIC_MIN

__all__ = ["FORM_TIE", "DEFER_MARGIN", "resolved_first", "deferred", "rival_forms", "same_place", "completes",
           "merge_completed"]


#: delta BIC within which two forms at one place tie (the one the data pin down goes first)
FORM_TIE = 2.0


def resolved_first(ranked: list) -> list:
    """``ranked`` (best first) with the best moved behind a rival form at its place that fits within
    :data:`FORM_TIE` when the best's form is one the data do not pin down (``form_unresolved``: a periodic
    error of a joint that turned less than one period, which any smooth error of that joint fits)."""
    if not ranked or not ranked[0].hyp.form_unresolved:
        return ranked
    top = ranked[0]
    for i, c in enumerate(ranked[1:], 1):
        if c.ev.dbic - top.ev.dbic > FORM_TIE:
            break
        if c.hyp.location == top.hyp.location and not c.hyp.form_unresolved:
            return [c] + ranked[:i] + ranked[i + 1:]
    return ranked


#: how much better (chi-square of the whitened residual) a hypothesis that defers to a commoner rival at its place
#: must fit than that rival to go first
DEFER_MARGIN = DBIC_MIN


def deferred(ranked: list) -> list:
    """``ranked`` (best first) with every candidate that defers to a rival at its place (``defers_to``: same
    location) moved behind that rival when the rival fits within :data:`DEFER_MARGIN` of it (the search tries the
    next candidates when the first fails, so every one keeps its margin, not only the best). A joint's zero shifted
    at one clamping position costs one parameter where the position's fixture pose costs three; where the ball's
    motion per radian of the joint hardly changes over the position's poses (joint 1 always: the ball stays at one
    place) the shift is a translation of that position and wins the BIC on any fixture offset along it: in rodlab's
    blind batch a 0.05 mm fixture offset had been named a shift of a joint and the validation got worse
    (0.038 -> 0.041 mm)."""
    out = list(ranked)
    i = 0
    while i < len(out):
        c = out[i]
        rival = next((j for j in range(i + 1, len(out)) if c.hyp.defers_to is not None
                      and out[j].hyp.effect == c.hyp.defers_to and out[j].hyp.location == c.hyp.location), None)
        if rival is not None and out[rival].rss - c.rss < DEFER_MARGIN:
            out.insert(i, out.pop(rival))             # the rival takes this place; the deferring one moves down
        else:
            i += 1
    return out


def rival_forms(best, ranked: list) -> list[str]:
    """Other effects or forms at the place of ``best`` that fit within delta BIC 10 of it: what the finding
    cannot rule out (one label per effect and form)."""
    out = []
    for c in ranked:
        h = c.hyp
        if (h is best.hyp or h.location != best.hyp.location or c.ev.dbic - best.ev.dbic >= DBIC_MIN
                or (h.effect == best.hyp.effect and h.names == best.hyp.names)):   # the same form at another grid setting
            continue
        label = h.label + _form_of(h)
        if label not in out:
            out.append(label)
    return out


def _form_of(h: Hypothesis) -> str:
    """The form of a hypothesis in words beyond its label's settings: a periodic error once or twice per
    revolution (told by its parameter names), a stiffening spring without saturation."""
    if h.effect == "periodic_joint_error":
        twice, once = any(n.startswith("amp2") for n in h.names), any(n.startswith("amp_") for n in h.names)
        return {(True, False): " (once per revolution)", (False, True): " (twice per revolution)",
                (True, True): " (once and twice per revolution)"}[(once, twice)]
    if h.effect == "joint_stiffening" and not h.settings:
        return " (no saturation)"
    return ""


def same_place(chosen: tuple, h: Hypothesis) -> bool:
    """``h`` is at a place the model already has: the same effect and location, or any angle error of a joint
    that already has one (a periodic error, backlash and a non-linear spring of one joint are competing forms,
    not parts: two of them split their shared part into large opposing terms that worsen the validation)."""
    effect, location = chosen
    if effect == h.effect and location == h.location:
        return True
    return bool(location) and location == h.location and str(location).startswith("joint:")


def completes(h: Hypothesis, accepted: list) -> bool:
    """``h`` is the other harmonic of a periodic error already accepted at its joint (``accepted``: the accepted
    hypotheses): together they are the once-and-twice form, offered only over a full turn (``h`` not
    ``form_unresolved``). A gear with a small once-per-revolution part beside a larger twice-per-revolution one had
    the twice form win the BIC and the rest left `unexplained` (rodlab's blind `shifts` batch: 2 of 8 named whole)."""
    if h.effect != "periodic_joint_error" or h.form_unresolved:
        return False
    here = [a for a in accepted if a.location == h.location]
    return (len(here) == 1 and here[0].effect == h.effect and not set(here[0].names) & set(h.names)
            and len(set(here[0].names) | set(h.names)) == 4)


def merge_completed(findings: list) -> list:
    """One finding per periodic error: a harmonic accepted to complete another at its joint (:func:`completes`)
    joins it (parameters and intervals of both; the rms after the second; the explanation of the whole form)."""
    out = []
    for f in findings:
        first = next((g for g in out if g.effect == f.effect == "periodic_joint_error" and g.location == f.location),
                     None)
        if first is None:
            out.append(f)
            continue
        first.parameters = {**first.parameters, **f.parameters}
        first.intervals = {**first.intervals, **f.intervals}
        first.rms_after_mm = f.rms_after_mm
        first.explanation = (f"a gear or encoder disc both eccentric and elliptical of joint {f.location.split(':')[1]}: "
                             "an angle error once and twice per revolution, periodic in q (the second harmonic found "
                             "beside the first)")
    return out
