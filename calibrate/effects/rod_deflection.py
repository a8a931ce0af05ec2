"""``rod_deflection``: the rod's deflection is compensated with the wrong compliance (or not at all)."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from rodlab.core.calc import calc_rod_compliance
from rodlab.core.compliance import RodCompliance
from rodlab.core.design_io import resolve_design
from rodlab.core.hypothesis import ParamSpec

from ..compensations import deflection_offsets
from .base import CampaignContext, CampaignEffectModel, Refit, hypothesis

__all__ = ["RodDeflection", "generic_rod"]


def generic_rod(rod: RodCompliance) -> RodCompliance:
    """A stand-in compliance for a rod known only by its tool vector and mass (a file with method ``none``):
    the built-in steel rod 4# with L1 / L2 taken from the tool vector's z / x, its closed form. Only its
    shape serves: the hypothesis scales its gravity and force parts separately."""
    x, _, z = (float(v) for v in rod.tool_mm)
    d = replace(resolve_design("rod4"), L1_mm=min(max(z, 120.0), 900.0), L2_mm=min(max(abs(x), 150.0), 900.0),
                name="generic")
    c = calc_rod_compliance(d)
    return replace(rod, method=c.method, C_F=c.C_F, C_g=c.C_g * (rod.mass_kg / c.mass_kg if c.mass_kg > 0 else 1.0))


def _has_matrices(rod: RodCompliance) -> bool:
    return bool(np.any(rod.C_F) or np.any(rod.C_g))


def scaled_rod(rod: RodCompliance, k: float, **provenance) -> RodCompliance:
    """``rod`` with both compliances (and r_rod) times ``k``; ``k <= 0`` (a fit's estimate of a rod far stiffer than
    its file, within its noise of 0) is a rigid rod: zero matrices, method ``none``."""
    if not k > 0:
        return RodCompliance.none_like(rod)
    return RodCompliance(rod.rod, rod.method, rod.C_F * k, rod.C_g * k, rod.mass_kg, rod.com_T_mm, rod.tool_mm,
                         rod.r_rod * k, dict(rod.provenance, **provenance) if provenance else rod.provenance)


class RodDeflection(CampaignEffectModel):
    effect = "rod_deflection"
    order = 20
    params = (ParamSpec("k", "-", "the true rod's compliance over the file's (both C_F and C_g)"),)
    example = {"k": 1.5}
    physics = "the compliance file does not match the rod (wrong method, wrong r_rod, another rod) or is zero"
    signature = "the residuals follow R_T^W (C_g g + C_F F), the compensated deflection, scaled"
    locations = ("null",)
    reported = ("`k` [-] (the true compliance over the file's; about 0: the rod is far stiffer than its file); "
                "or `k_gravity`, `k_force` [-]: the deflection under the rod's weight and under the contact force "
                "scaled apart (another rod's file; when the file's matrices are zero, method `none`, the shape of a "
                "generic steel rod fitted to the tool vector)")

    def check(self, p: dict) -> None:
        if not p["k"] > 0:
            self.fail(f"effect {self.effect}: k must be > 0 (a compliance ratio), got {p['k']}", f"{self.effect}.k")

    def true_rod(self, rod, p: dict):
        return scaled_rod(rod, float(p["k"]))

    def hypotheses(self, ctx: CampaignContext) -> list:
        rod, obs = ctx.rod, ctx.obs
        if rod is None:
            return []
        N = ctx.n_points
        defl = deflection_offsets(ctx.robot, ctx.result.params, obs.q_rad, obs.force_W_N, rod)
        if not np.any(defl):
            return [self._uncompensated(ctx)]
        parts = [deflection_offsets(ctx.robot, ctx.result.params, obs.q_rad, obs.force_W_N, replace(rod, C_F=0 * rod.C_F)),
                 deflection_offsets(ctx.robot, ctx.result.params, obs.q_rad, obs.force_W_N, replace(rod, C_g=0 * rod.C_g))]
        return [hypothesis(self.effect, None, ["k"], defl.reshape(3 * N, 1),
                           "the rod's deflection is compensated with the wrong compliance: residuals follow "
                           "R_T^W (C_g g^T + C_F F^T) scaled by a factor", report_offset=[1.0]),
                hypothesis(self.effect, None, ["k_gravity", "k_force"],
                           np.stack([c.reshape(-1) for c in parts], axis=1),
                           "the compliance file is another rod's: residuals follow its deflection under its weight "
                           "and under the contact force, each scaled by its own factor", report_offset=[1.0, 1.0])]

    def _uncompensated(self, ctx: CampaignContext):
        """The compliance file's matrices are zero: the residuals follow a rod's deflection (gravity and
        contact-force parts scaled separately) that nothing compensated."""
        g, obs = generic_rod(ctx.rod), ctx.obs
        cols = [deflection_offsets(ctx.robot, ctx.result.params, obs.q_rad, obs.force_W_N, replace(g, C_F=0 * g.C_F)),
                deflection_offsets(ctx.robot, ctx.result.params, obs.q_rad, obs.force_W_N, replace(g, C_g=0 * g.C_g))]
        H = np.stack([c.reshape(-1) for c in cols], axis=1)
        return hypothesis(self.effect, None, ["k_gravity", "k_force"], H,
                          "the rod's deflection is not compensated (the compliance file has zero matrices): the "
                          "residuals follow a cantilever's deflection under its weight and the contact force")

    def refit(self, fit: Refit, location: str, parameters: dict, ctx: CampaignContext) -> None:
        if "k_force" in parameters:        # the two parts scaled: the file's, or the stand-in's for a zero file
            g = ctx.rod if _has_matrices(ctx.rod) else generic_rod(ctx.rod)
            fit.rod = replace(g, C_F=g.C_F * max(parameters["k_force"], 0.0),
                              C_g=g.C_g * max(parameters["k_gravity"], 0.0))
        else:
            k = parameters["k"]
            fit.rod = scaled_rod(ctx.rod, k, diagnosis_scale=k)

    def remedy(self, location: str, parameters: dict) -> str:
        k = parameters.get("k")
        if k is not None and k < -0.3:
            return (f"the residuals run against the compensation (k = {k:.2g}): a rod stiffer than its file gives k "
                    "near 0, not below; check the compliance file's frame and signs ({T} axes, the gravity "
                    "direction, C_F's sign) and that it is this rod's file")
        if k is not None and k < 0.05:
            return (f"the rod deflects far less than its compliance file says (k = {k:.2g}): the file is of another, "
                    "softer rod or of the wrong method; calibrate with this rod's own file (`rodlab rig fit` or "
                    "`rodlab fea`), or `--compensation none` for a rigid rod")
        if k is None:
            return (f"the rod deflects {parameters['k_gravity']:.3g}x under its weight and {parameters['k_force']:.3g}x "
                    "under the contact force what the compliance file says (a file of another rod, or with zero "
                    "matrices: then of a generic steel rod's shape): calibrate with this rod's own file (`rodlab rig "
                    "fit` writes a measured one, `rodlab fea` a simulated one; `--rod FILE --compensation file`)")
        return (f"the compliance file is off by a factor {k:.3g}: measure the rod on the stiffness rig "
                "(`rodlab rig fit` writes a measured file) and calibrate with that file")
