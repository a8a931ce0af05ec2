"""The one selection routine of both diagnosers: grow the model one term at a time and, at each step, try the
candidates best first against the shared acceptance rule (:mod:`.criteria`).

What differs between the rig and a campaign is what a candidate is and which checks may let the next one try;
each says so in a :class:`SearchSpace`:

- the rig (:mod:`.rig_select`) keeps a beam of the best subsets of each size (subsets need not nest, so a step
  without an accepted model does not end the search: ``keep_growing``); a candidate off its physical bounds or
  below the detection limit lets the next one try, one that fails significance or cross-validation ends the
  step; afterwards a drop-one test and swaps (``finish``);
- a campaign (:mod:`.campaign`) extends the current model only, with one extra outlier point per step; any
  failed check lets the next significant candidate try (``FALLBACKS`` of them), and a step without an accepted
  candidate ends the search.
"""
from __future__ import annotations

from typing import Protocol, Sequence

from rodlab.core.enums import Trial

__all__ = ["SearchSpace", "search"]


class SearchSpace(Protocol):
    """A diagnoser's hypotheses over its data, and its current model (the space holds the state).

    tries : candidates tried per step, best first
    keep_growing : a step that accepts nothing does not end the search (a beam: the next size may pass)
    """

    tries: int
    keep_growing: bool

    def exhausted(self) -> bool:
        """The current model is as large as allowed."""

    def grow(self) -> Sequence:
        """The candidate models with one more term, best first (empty: nothing left to add)."""

    def trial(self, candidate) -> Trial:
        """Apply the acceptance rule to ``candidate``; on :attr:`Trial.ACCEPT` it is now the current model."""

    def finish(self) -> None:
        """Tidy the final model (e.g. a drop-one test)."""


def search(space: SearchSpace, max_steps: int) -> None:
    """Run at most ``max_steps`` selection steps on ``space``; the selected model is the space's current one."""
    for _ in range(max_steps):
        if space.exhausted():
            break
        ranked = space.grow()
        if not ranked:
            break
        if not _step(space, ranked[:space.tries]) and not space.keep_growing:
            break
    space.finish()


def _step(space: SearchSpace, candidates: Sequence) -> bool:
    """Try ``candidates`` in order until one is accepted (True) or one ends the step."""
    for cand in candidates:
        outcome = space.trial(cand)
        if outcome is Trial.ACCEPT:
            return True
        if outcome is Trial.END_STEP:
            return False
    return False
