"""What a simulated compliance is worth: the envelope around it inside which the rod as built may lie.

A simulation is never the rod. The envelope of a C_F entry combines (a) the design's tolerances
(:mod:`rodlab.core.tolerances`: tube OD and wall, laminate E and G, bend radius, ring length), through the frame model of
the perturbed design (the as-built fit of :mod:`.rig_form`), and (b) the simulation method's own bias and scatter
against the solid FEA (:data:`rodlab.core.sensitivity.METHOD_ACCURACY`). Without a
design the envelope is one relative standard deviation per entry; ``exact`` says the simulation is the rod (a
re-check against an earlier measurement of the same rod).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from rodlab.fea.frame import frame_compliance

from ...core.compliance import RodCompliance, design_hash
from ...core.design_io import load_design
from ...core.enums import Method, SimAccuracy
from ...core.errors import DesignError, RodlabError
from ...core.joint_springs import design_joint_places, spring_matrices
from ...core.sensitivity import STRUCTURAL_ENTRIES, MethodAccuracy, method_accuracy, with_values
from ...core.tolerances import bond_tolerances, design_tolerances

__all__ = ["Envelope", "envelope_for", "design_of", "MEAS_RELATIVE", "GENERIC_RELATIVE"]

log = logging.getLogger(__name__)

#: relative standard deviation of a measured compliance file's entries when it states none (remounting the rod
#: on the rig and re-fitting repeats C_F to about this)
MEAS_RELATIVE = 0.01
#: relative standard deviation per entry of a simulation whose design is unknown (a laminate's modulus alone
#: scatters this much: :data:`rodlab.core.tolerances.DEFAULT_RULES`)
GENERIC_RELATIVE = 0.15


@dataclass(frozen=True)
class Envelope:
    """How far the rod's C_F may lie from the simulated one.

    kind : :class:`~rodlab.core.enums.SimAccuracy`; C_sim : simulated C_F [mm/N], shape=(3, 3); params : the design's
    uncertain keys (:class:`~rodlab.core.tolerances.ToleranceParam`); accuracy : the simulation method's bias and
    scatter against the solid FEA
    (:class:`~rodlab.core.sensitivity.MethodAccuracy`; without a design, the whole envelope); source : one line
    saying what the envelope is made of; model : design ->
    C_F [mm/N] (the frame) and design : the design, for the as-built fit (:meth:`entries_at`); ratio : simulated
    over model C_F with the method's bias removed, entry by entry, shape=(3, 3) (the simulation's own form kept as
    the as-built keys move);
    bonds : the design's bonds as ((place, sigma [rad/(N m)], d C_F / d s_bend [mm/N per rad/(N m)], shape=(3, 3)),
    ...): standardised deviations after the keys'; u_bounds : the range of each key's and bond's standardised
    deviation the design rules allow (within +-4), shape=(k + bonds, 2)
    """

    kind: SimAccuracy
    C_sim: np.ndarray
    params: tuple = ()
    accuracy: MethodAccuracy = field(default_factory=lambda: MethodAccuracy.uniform("exact", 0.0))
    source: str = ""
    model: object = None
    design: object = None
    ratio: np.ndarray = field(default_factory=lambda: np.ones((3, 3)))
    bonds: tuple = ()
    u_bounds: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))

    def __post_init__(self) -> None:
        object.__setattr__(self, "kind", SimAccuracy.parse(self.kind, "simulation accuracy"))
        if np.shape(self.C_sim) != (3, 3) or np.shape(self.ratio) != (3, 3):
            raise ValueError(f"Envelope: C_sim and ratio (3, 3) expected, got {np.shape(self.C_sim)}, "
                             f"{np.shape(self.ratio)}")

    @property
    def exact(self) -> bool:
        return self.kind is SimAccuracy.EXACT

    @property
    def n_free(self) -> int:
        """Standardised deviations of the as-built fit: the keys', then the bonds'."""
        return len(self.params) + len(self.bonds) if self.model is not None else 0

    def values(self, u: np.ndarray) -> dict:
        """The as-built keys for standardised log deviations ``u`` (a key is ``nominal exp(u sigma / nominal)``:
        moduli and sizes stay positive, and a compliance ~ 1/E is linear in u)."""
        return {p.key: p.nominal * float(np.exp(ui * p.relative)) for p, ui in zip(self.params, u)}

    def entries_at(self, u: np.ndarray, entries) -> np.ndarray:
        """C_F entries of the rod as built at ``u`` [mm/N]: the model of the perturbed design times :attr:`ratio`."""
        if self.n_free == 0:
            return self.accuracy.expected(self.C_sim, entries)
        C = np.asarray(self.model(self.design_at(u[:len(self.params)])), float) * self.ratio
        for (_, sd, dC), ub in zip(self.bonds, u[len(self.params):]):
            C = C + sd * ub * dC
        return np.array([C[m, n] for m, n in entries])

    def design_at(self, u: np.ndarray):
        """The design with the keys at standardised deviations ``u``, or where the design rules refuse it, at
        :meth:`accepted_u`."""
        return self._accepted(u)[1]

    def accepted_u(self, u: np.ndarray) -> np.ndarray:
        """``u`` where the design rules accept the design; else ``u`` with its geometric keys (not the
        materials', which no rule limits) scaled back towards the nominal design until they do (keys moved
        together past what each allows alone: a longer ring and a larger bend radius on a pipe with no free length
        left), so a fit that strays there sees the model stop changing instead of an error, and reports the keys
        the model was evaluated at."""
        return self._accepted(u)[0]

    def _accepted(self, u: np.ndarray):
        u = np.asarray(u, float)
        try:
            return u, with_values(self.design, self.values(u))
        except DesignError:
            pass
        geometric = np.array([not p.key.startswith("materials.") for p in self.params])
        good, bad, design = 0.0, 1.0, None
        for _ in range(12):
            mid = 0.5 * (good + bad)
            try:
                design, good = with_values(self.design, self.values(np.where(geometric, mid * u, u))), mid
            except DesignError:
                bad = mid
        used = np.where(geometric, good * u, u)
        return used, design if design is not None else with_values(self.design, self.values(used))

    def bond_columns(self, entries) -> np.ndarray:
        """d entries / d u of the bonds' standardised deviations [mm/N], shape=(len(entries), bonds): exact, the
        entries are linear in them (:meth:`entries_at`)."""
        out = np.zeros((len(entries), len(self.bonds)))
        for j, (_, sd, dC) in enumerate(self.bonds):
            out[:, j] = [sd * dC[m, n] for m, n in entries]
        return out


def design_of(sim: RodCompliance, design=None):
    """The design a simulated compliance was made from: ``design`` when given, else the file its provenance names
    when that file still hashes to the recorded design; None otherwise."""
    if design is not None:
        return design
    path = sim.provenance.get("design_file")
    if not path or not Path(path).is_file():
        return None
    try:
        found = load_design(path)
    except RodlabError:
        return None
    if sim.provenance.get("design_sha256") not in (None, design_hash(found)):
        log.warning("%s changed since the compliance was simulated; its tolerances are not used", path)
        return None
    return found


def envelope_for(sim: RodCompliance, design=None, accuracy: str | float | None = None) -> Envelope:
    """The envelope around ``sim``: ``accuracy`` ``exact``, a relative standard deviation per entry (float), or
    None / ``design``: from the design's tolerances and the method's accuracy (a measured file: its stated or a
    1 % accuracy; a simulation without a known design: :data:`GENERIC_RELATIVE`)."""
    C = np.asarray(sim.C_F, float)
    if accuracy is not None and not isinstance(accuracy, str):
        rel = float(accuracy)
        found = design_of(sim, design) if sim.method not in (Method.MEAS, Method.NONE) else None
        if found is not None:                  # a trial: a stated accuracy had dropped the design's tolerances
            return _design_envelope(sim, found, stated=rel)
        return Envelope(SimAccuracy.RELATIVE, C, accuracy=MethodAccuracy.uniform("stated", rel),
                        source=f"{rel:.1%} per C_F entry (stated)")
    kind = SimAccuracy.parse(accuracy or "design", "simulation accuracy")
    if kind is SimAccuracy.EXACT:
        return Envelope(kind, C, source="the simulation is the rod (exact)")
    if kind is SimAccuracy.RELATIVE:
        raise RodlabError("--sim-accuracy relative needs a number: give the relative accuracy, e.g. 0.05 for 5 %")
    if sim.method is Method.MEAS:
        return _measured_envelope(sim)
    found = design_of(sim, design)
    if found is None or sim.method is Method.NONE:
        return Envelope(SimAccuracy.RELATIVE, C, accuracy=MethodAccuracy.uniform("no design", GENERIC_RELATIVE),
                        source=f"no design known: {GENERIC_RELATIVE:.0%} per C_F entry (give --design DESIGN.rod.toml "
                               "for its tolerances)")
    return _design_envelope(sim, found)


def _measured_envelope(sim: RodCompliance) -> Envelope:
    """A measured compliance: its stated standard uncertainty (``C_F_sigma_mm_per_N``, compliance/2) with the
    :data:`MEAS_RELATIVE` of remounting and refitting added in quadrature, per entry."""
    rel = np.full(4, MEAS_RELATIVE)
    if sim.C_F_sigma is not None:
        for i, (m, n) in enumerate(STRUCTURAL_ENTRIES):
            sd, c = sim.C_F_sigma[m, n], sim.C_F[m, n]
            if np.isfinite(sd) and c:
                rel[i] = float(np.hypot(sd / abs(c), MEAS_RELATIVE))
    acc = MethodAccuracy("measured", np.zeros(4), rel, np.eye(4))
    return Envelope(SimAccuracy.RELATIVE, np.asarray(sim.C_F, float), accuracy=acc,
                    source="a measured compliance: its stated uncertainty and " f"{MEAS_RELATIVE:.0%} per entry "
                           "(remounting and refitting)")


def _design_envelope(sim: RodCompliance, design, stated: float | None = None) -> Envelope:
    """Tolerances of ``design`` through the frame model of the perturbed design (its form scaled entry by entry to
    the simulated compliance, the method's bias removed) plus the accuracy of the method that made ``sim``, or the
    ``stated`` relative accuracy per entry instead of it."""

    def model(d):
        return frame_compliance(d)[0]
    params = tuple(design_tolerances(design))
    C_model = model(design)
    C = np.asarray(sim.C_F, float)
    method = str(sim.method)
    kind = sim.provenance.get("model")
    acc = method_accuracy(method, kind) if stated is None else MethodAccuracy.uniform("stated", stated)
    unbiased = np.ones((3, 3))
    for (m, n), b in zip(STRUCTURAL_ENTRIES, acc.bias):
        unbiased[m, n] = unbiased[n, m] = np.exp(-b)
    ratio = np.where(np.abs(C_model) > 1e-12 * np.abs(C_model).max(), C / np.where(C_model == 0, 1, C_model), 1.0)
    label = f"{method}" + (f" ({kind})" if kind else "")
    keys = ", ".join(f"{p.key} {p.relative:.1%}" for p in params)
    against = (f"{label}: {stated:.1%} per entry (stated)" if stated is not None else
               f"{label}: {acc.sd[0]:.1%} per entry (its mesh and its idealised geometry: perfect bonds, sharp "
               f"corners)" if kind == "solid" else f"{label} against the solid FEA: bias "
               + ", ".join(f"c{m + 1}{n + 1} {b:+.1%}" for (m, n), b in zip(STRUCTURAL_ENTRIES, acc.bias))
               + ", scatter " + ", ".join(f"{v:.1%}" for v in acc.sd))
    env = Envelope(SimAccuracy.DESIGN, C, params, acc,
                   f"design {design.name}: tolerances {keys}; {against}; bonds "
                   + ", ".join(f"{p} {sd:.1g}" for p, sd in bond_tolerances(design).items()) + " rad/(N m)",
                   model, design, ratio * unbiased, _bonds(design))
    # a bond only softens below its design value: a rigid one (the default) from 0, a declared one down to 0
    declared = [design.joints[b[0]].s_bend_rad_per_Nm if b[0] in design.joints else 0.0 for b in env.bonds]
    lower = [max(-4.0, -s / b[1]) for s, b in zip(declared, env.bonds)]
    bounds = np.vstack([_feasible_bounds(env), np.column_stack([lower, np.full(len(lower), 4.0)])])
    return replace(env, u_bounds=bounds.reshape(-1, 2))


def _bonds(design) -> tuple:
    """(place, sigma, d C_F / d s_bend) of each toleranced bond: a rotational spring across the member there."""
    places = design_joint_places(design)
    out = []
    for place, sd in bond_tolerances(design).items():
        if place in places:
            Cb, _ = spring_matrices(places[place].point_T_mm, places[place].axis_T)
            out.append((place, sd, 1e-3 * Cb))
    return tuple(out)


def _feasible_bounds(env: Envelope, reach: float = 4.0) -> np.ndarray:
    """Per key, the standardised deviations within +-``reach`` for which the design rules accept the design (a bend
    cannot be made tighter than 1.5 tube diameters, ...): bisection where the full reach is refused, with a 5 %
    margin for keys moved together."""
    k = len(env.params)
    out = np.tile([-reach, reach], (k, 1))

    def ok(i, u):
        v = np.zeros(k)
        v[i] = u
        try:
            with_values(env.design, env.values(v))
            return True
        except DesignError:
            return False
    for i in range(k):
        for j, end in enumerate((-reach, reach)):
            if ok(i, end):
                continue
            good, bad = 0.0, end
            for _ in range(12):
                mid = 0.5 * (good + bad)
                good, bad = (mid, bad) if ok(i, mid) else (good, mid)
            out[i, j] = 0.95 * good
    return out
