"""The diagnosers' one selection routine (rodlab.app.diagnose.search): its step semantics, and forward selection
under the shared acceptance rule recovering the true terms of a known linear model."""
from __future__ import annotations

import numpy as np

from rodlab.app.diagnose.criteria import bic_penalty, evidence
from rodlab.app.diagnose.search import search
from rodlab.core.enums import Trial


class _Scripted:
    """Candidates and outcomes given in advance; records what was tried."""

    def __init__(self, steps, tries=10, keep_growing=False, limit=None):
        self.steps, self.tries, self.keep_growing, self.limit = list(steps), tries, keep_growing, limit
        self.tried, self.accepted, self.finished = [], [], False

    def exhausted(self):
        return self.limit is not None and len(self.accepted) >= self.limit

    def grow(self):
        return self.steps.pop(0) if self.steps else []

    def trial(self, cand):
        name, outcome = cand
        self.tried.append(name)
        if outcome is Trial.ACCEPT:
            self.accepted.append(name)
        return outcome

    def finish(self):
        self.finished = True


def test_next_lets_the_next_try_and_end_step_ends_the_step():
    space = _Scripted([[("a", Trial.NEXT), ("b", Trial.ACCEPT), ("c", Trial.ACCEPT)],
                       [("d", Trial.END_STEP), ("e", Trial.ACCEPT)]])
    search(space, 5)
    assert space.tried == ["a", "b", "d"]          # c not tried after b; e not tried after d ended the step
    assert space.accepted == ["b"] and space.finished


def test_a_beam_keeps_growing_after_a_step_without_a_model():
    steps = [[("a", Trial.END_STEP)], [("b", Trial.ACCEPT)]]
    stop = _Scripted(steps)
    search(stop, 5)
    assert stop.accepted == []
    beam = _Scripted(steps, keep_growing=True)
    search(beam, 5)
    assert beam.accepted == ["b"]


def test_tries_and_max_steps_bound_the_search():
    space = _Scripted([[("a", Trial.NEXT), ("b", Trial.NEXT), ("c", Trial.ACCEPT)]], tries=2)
    search(space, 5)
    assert space.tried == ["a", "b"] and space.accepted == []
    many = _Scripted([[("x%d" % i, Trial.ACCEPT)] for i in range(10)], keep_growing=True)
    search(many, 3)
    assert many.accepted == ["x0", "x1", "x2"]


def test_the_search_stops_when_the_model_is_as_large_as_allowed():
    space = _Scripted([[("x%d" % i, Trial.ACCEPT)] for i in range(5)], keep_growing=True, limit=2)
    search(space, 10)
    assert space.accepted == ["x0", "x1"] and space.finished


class _Forward:
    """Forward selection of polynomial terms x^k by the shared rule (known noise)."""

    tries, keep_growing = 3, False

    def __init__(self, x, y, sigma):
        self.X = np.column_stack([x ** k for k in range(1, 6)])
        self.y, self.sigma, self.cur = y - y.mean(), sigma, ()
        self.rss = float(self.y @ self.y)

    def _rss(self, S):
        A = self.X[:, list(S)] - self.X[:, list(S)].mean(axis=0)
        e = self.y - A @ np.linalg.lstsq(A, self.y, rcond=None)[0]
        return float(e @ e)

    def exhausted(self):
        return len(self.cur) >= 4

    def grow(self):
        cands = [(self.cur + (k,), self._rss(self.cur + (k,))) for k in range(5) if k not in self.cur]
        return sorted(cands, key=lambda c: c[1])

    def trial(self, cand):
        S, rss = cand
        if not evidence((self.rss - rss) / self.sigma ** 2, 1, bic_penalty(1, self.y.size)).significant:
            return Trial.END_STEP
        self.cur, self.rss = S, rss
        return Trial.ACCEPT

    def finish(self):
        pass


def test_forward_selection_recovers_the_true_terms():
    rng = np.random.default_rng(3)
    x = rng.uniform(-1, 1, 400)
    sigma = 0.01
    y = 0.3 * x + 0.2 * x ** 3 + sigma * rng.standard_normal(x.size)
    space = _Forward(x, y, sigma)
    search(space, 10)
    assert sorted(space.cur) == [0, 2]             # x and x^3, nothing else
    assert space.rss / sigma ** 2 < 1.2 * x.size   # the fit is at the noise
    null = _Forward(x, sigma * rng.standard_normal(x.size), sigma)
    search(null, 10)
    assert null.cur == ()
