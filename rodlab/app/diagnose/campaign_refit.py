"""The campaign identified again with the diagnosis' findings, and the validation before and after.

Each finding's effect says how it enters (:meth:`~rodlab.calibrate.effects.CampaignEffectModel.refit`): freed
fixture offsets, a rescaled compliance, dropped outliers, joint-angle corrections (periodic errors also at the
validation points, as a controller would apply them), edits of the observations (points referred back to the
campaign start, backlash, a non-linear spring).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
from rodlab.calibrate import FitOptions, ModelParams, Rod, RodDeflection, campaign_observations, identify, validate
from rodlab.calibrate.effects import CampaignContext, Refit, campaign_effect, correct_joints
from rodlab.calibrate.kinematics import ball_positions
from rodlab.calibrate.points import points_observations

__all__ = ["deflection_of", "reidentify", "validation_errors", "after_errors"]


def deflection_of(rod):
    """The deflection of the compliance file ``rod`` as it stands (its matrices, whatever its method says)."""
    return RodDeflection(Rod.of(rod), str(rod.method))


def reidentify(robot, camp, fix, rod, ctx: CampaignContext, findings, noise_mm, fixture_sigma):
    """Identify the campaign again with the found physics (each effect says how: :meth:`refit`); returns the
    result and the :class:`Refit` it used. A non-linear joint spring is applied whole and with its linear part
    left to the joint's compliance (:class:`~rodlab.calibrate.effects.joint_stiffening.TorqueCorrection`): the
    better fit is kept."""
    best = None
    for linear_to_c in (False, True):
        fit = Refit(rod, np.ones(ctx.n_points, dtype=bool), torque_linear_to_c=linear_to_c)
        for f in findings:
            campaign_effect(f.effect).refit(fit, f.location, f.parameters, ctx)
        res2 = _identify_with(robot, camp, fix, rod, fit, noise_mm, fixture_sigma, ctx)
        if best is None or res2.rms_mm < best[0].rms_mm:
            best = (res2, fit)
        if not fit.torque_corrections:
            break
    return best


def _identify_with(robot, camp, fix, rod, fit: Refit, noise_mm, fixture_sigma, ctx: CampaignContext):
    """The identification of the campaign edited by ``fit``."""
    obs2 = campaign_observations(camp, fix, fit.rod)
    # the joints really turn by q + a_s sin q + a_c cos q (residual = measured - model = g (a_s sin + a_c cos))
    obs2 = replace(obs2, q_rad=correct_joints(obs2.q_rad, fit.joint_corrections_rad))
    for edit in fit.obs_edits:
        obs2 = edit(obs2)
    if not fit.keep.all():
        obs2 = obs2.subset(fit.keep)
    return identify(robot, obs2, Rod.of(rod), [deflection_of(fit.rod)],
                    FitOptions(freed=fit.freed, expected_noise_mm=noise_mm, fixture_sigma=fixture_sigma,
                               harmonics=tuple(ctx.result.harmonic_range_deg)))


def validation_errors(robot, fits, points) -> dict:
    """Position errors at the validation points: nominal model, identified, identified with the found physics
    (joint angles corrected as a controller would); ``fits``: the :class:`~.campaign_fits.CampaignFits`."""
    after = fits.after if fits.after is not None else fits.before
    return {"nominal": validate(robot, ModelParams.nominal(robot, points.tool_mm), points)[1],
            "before": validate(robot, fits.before.params, points)[1],
            "after": after_errors(robot, after.params, fits.joint_corrections_rad, fits.torque_corrections, points)}


def after_errors(robot, params, joint_corrections_rad: dict, torque_corrections: dict, points) -> np.ndarray:
    """Position errors [mm] at the validation points of the model ``params`` with the found joint corrections
    applied to the points' angles, as a controller would (periodic errors; non-linear springs at the points' own
    torques)."""
    if joint_corrections_rad:
        points = replace(points, q_deg=np.rad2deg(correct_joints(np.deg2rad(points.q_deg), joint_corrections_rad)))
    if torque_corrections:
        points = _torque_corrected(robot, params, points, torque_corrections)
    return validate(robot, params, points)[1]


def _torque_corrected(robot, params, points, corrections: dict):
    """``points`` with each non-linear joint spring's turn (:func:`~rodlab.calibrate.effects.joint_stiffening.
    TorqueCorrection.turn`) added, at the static torques the model ``params`` gives them under their own rod (the
    validation rod's weight); ``corrections``: {joint index: its TorqueCorrection}."""
    obs = points_observations(points)
    _, tau = ball_positions(robot, params, obs.q_rad, obs.rod)
    q = np.deg2rad(np.asarray(points.q_deg, float)).copy()
    for k, correction in corrections.items():
        q[:, k] += correction.turn(tau[:, k])
    return replace(points, q_deg=np.rad2deg(q))
