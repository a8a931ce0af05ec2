"""update --sim: the user's own simulation moved with the keys as rodlab's frame moves (update.model_compliance)."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from rodlab import calc_rod_compliance, resolve_design
from rodlab.app.update import SMALL_ENTRY, model_compliance
from rodlab.core.sensitivity import with_values
from rodlab.fea.frame import frame_compliance


def test_the_users_simulation_moves_in_proportion_where_the_frame_resolves_an_entry_and_by_its_change_elsewhere():
    design = resolve_design("rod1")
    base = frame_compliance(design)[0]
    user = replace(calc_rod_compliance(design), C_F=base * 1.04 + 2e-5 * (np.abs(base) < 1e-12))   # its own model
    moved = model_compliance("frame", user, design)
    assert np.allclose(moved(design), user.C_F)                               # the design gives the user's file back
    thinner = with_values(design, {"tube.wall_mm": design.pipe_I.wall_mm * 0.9})
    frame_d = frame_compliance(thinner)[0]
    d = np.sqrt(np.abs(np.diag(base)))
    scaled = np.abs(base) > SMALL_ENTRY * np.outer(d, d)
    assert scaled[0, 0] and scaled[2, 2] and not scaled[0, 1]                 # c12: a structural zero of a planar rod
    assert np.allclose(moved(thinner)[scaled], (user.C_F * frame_d / np.where(scaled, base, 1.0))[scaled])
    assert np.allclose(moved(thinner)[~scaled], (user.C_F + frame_d - base)[~scaled])
    assert np.all(np.isfinite(moved(thinner)))
