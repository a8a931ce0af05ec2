"""The position share test of an unexplained campaign excess (rodlab.app.diagnose.spread): calibrated under
its null (leverage and the correlation of the shares accounted for), powerful against one noisy position."""
from __future__ import annotations

import numpy as np
import pytest

from rodlab.app.diagnose.spread import ShareTest, position_share_test

N_POS, PER = 5, 6


def _layout(rng, p=18):
    """A fit with uneven leverage: some columns act on one position only (as fixture terms do)."""
    n = 3 * N_POS * PER
    A = rng.standard_normal((n, p))
    A[:, :4] *= np.repeat(np.arange(N_POS * PER) < PER, 3)[:, None] * 5.0      # position 0 leans on 4 columns
    return A, np.repeat(np.arange(N_POS), PER)


def _resid(A, e):
    Q, _ = np.linalg.qr(A)
    return e - Q @ (Q.T @ e)


def test_p_is_uniform_under_the_null():
    rng = np.random.default_rng(11)
    A, pos = _layout(rng)
    kept = np.ones(pos.size, bool)
    p = np.array([position_share_test(_resid(A, rng.standard_normal(A.shape[0])), A, pos, kept).p
                  for _ in range(200)])
    assert 0.02 <= np.mean(p <= 0.1) <= 0.2          # nominal 0.1; 300 draws: SD 0.017
    assert 0.38 <= np.mean(p <= 0.5) <= 0.62


def test_one_noisy_position_is_found():
    rng = np.random.default_rng(5)
    A, pos = _layout(rng)
    scale = np.where(np.repeat(pos, 3) == 3, 3.0, 1.0)
    res = position_share_test(_resid(A, scale * rng.standard_normal(A.shape[0])), A, pos, np.ones(pos.size, bool))
    assert res.worst == 3 and res.p < 0.01
    assert max(res.shares, key=res.shares.get) == 3 and abs(sum(res.shares.values()) - 1) < 1e-12


def test_the_null_covariance_is_followed():
    """Noise whose whitened covariance is not the identity (the device noisier than stated, the fixture
    poses not): with that covariance as the null the test is calibrated; with the identity it is not."""
    rng = np.random.default_rng(8)
    A, pos = _layout(rng)
    var = np.repeat(np.where(np.arange(N_POS) < 2, 4.0, 1.0), 3 * PER)            # positions 0, 1 noisier
    C = np.diag(var)
    kept = np.ones(pos.size, bool)
    e = [_resid(A, np.sqrt(var) * rng.standard_normal(A.shape[0])) for _ in range(120)]
    p_null = np.array([position_share_test(x, A, pos, kept, C).p for x in e])
    p_white = np.array([position_share_test(x, A, pos, kept).p for x in e])
    assert 0.03 <= np.mean(p_null <= 0.1) <= 0.2
    assert 0.35 <= np.mean(p_null <= 0.5) <= 0.65
    assert np.mean(p_white <= 0.1) > 0.5


def test_the_fit_leverage_is_accounted_for():
    """Columns acting on position 0 only (a fixture pose) leave it little residual: without the projector in the
    null draws the test would call the other positions noisy; with it p stays uniform."""
    rng = np.random.default_rng(21)
    n = 3 * N_POS * PER
    on0 = np.repeat(np.repeat(np.arange(N_POS), PER) == 0, 3)
    A = np.column_stack([rng.standard_normal((n, 6)), rng.standard_normal((n, 9)) * on0[:, None]])
    pos, kept = np.repeat(np.arange(N_POS), PER), np.ones(N_POS * PER, bool)
    p = np.array([position_share_test(_resid(A, rng.standard_normal(n)), A, pos, kept).p for _ in range(150)])
    assert 0.03 <= np.mean(p <= 0.1) <= 0.2
    assert 0.35 <= np.mean(p <= 0.5) <= 0.65


def test_a_position_the_fit_explains_completely_is_left_out():
    rng = np.random.default_rng(4)
    pos = np.concatenate([np.repeat(np.arange(4), PER), [4]])           # position 4: one point
    n = 3 * pos.size
    own = np.zeros((n, 3))
    own[-3:] = np.eye(3)                                              # its own fixture offset: no residual left
    A = np.column_stack([rng.standard_normal((n, 10)), own])
    for _ in range(20):
        res = position_share_test(_resid(A, rng.standard_normal(n)), A, pos, np.ones(pos.size, bool))
        assert res.worst != 4 and res.p > 1e-3
    one = position_share_test(_resid(A, rng.standard_normal(n)), A, np.zeros(pos.size, int), np.ones(pos.size, bool))
    assert one.p == 1.0


def test_dropped_points_are_left_out_and_p_is_checked():
    rng = np.random.default_rng(2)
    A, pos = _layout(rng)
    e = _resid(A, rng.standard_normal(A.shape[0]))
    e[:3] = 100.0                                    # a gross error at point 0 (position 0), dropped
    kept = np.ones(pos.size, bool)
    kept[0] = False
    res = position_share_test(e, A, pos, kept)
    assert res.p > 1e-3
    with pytest.raises(ValueError, match="p must lie"):
        ShareTest(0, 1.5, {})
