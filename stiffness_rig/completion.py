"""The measured compliance file's C_F from a recording that did not load every axis.

The rig measures the columns of C_F its loads excite (all three gauges under a load along one axis); an entry no
load measured is taken as r_rod x the simulated one (paper Eq. 21/22). Mixed with measured entries, that guess
can contradict them: a rod whose flange bond or ring joint is softer than simulated has measured c_xz and c_zz
larger than r_rod x simulated c_xx allows, so the completed matrix is not positive semi-definite, which no rod's
compliance can be (and a compliance file may not be). :func:`complete_c_f` then raises the unmeasured diagonal
entries to the smallest values the measured entries require (the Schur complement of the measured block) and says
so; measured entries that contradict one another are refused, naming the entries.
"""
from __future__ import annotations

import numpy as np

from .errors import RigError

__all__ = ["complete_c_f"]

#: the margin above the smallest consistent value [relative], so that the file's C_F is safely positive definite
_MARGIN = 1e-3


def complete_c_f(measured: np.ndarray, guess: np.ndarray, source: str = "",
                 guess_is: str = "r_rod x simulated") -> tuple[np.ndarray, list[str]]:
    """C_F [mm/N], shape=(3, 3): the ``measured`` entries (NaN where not measured; the two of a pair averaged),
    ``guess`` (r_rod x simulated) for the rest, unmeasured diagonal entries raised where the measured entries
    need it; and the notes to tell the user. ``source``: the recording, ``guess_is``: what ``guess`` is, for the
    messages."""
    C = _filled(measured, guess)
    if _is_psd(C):
        return C, []
    seen = np.isfinite(np.diag(measured))
    m, u = np.nonzero(seen)[0], np.nonzero(~seen)[0]
    where = f"{source}: " if source else ""
    if u.size == 0 or not _is_psd(C[np.ix_(m, m)]):
        raise RigError(f"{where}the measured compliance entries contradict one another (C_F is not positive "
                       f"semi-definite: eigenvalues {np.linalg.eigvalsh(0.5 * (C + C.T))}); check the gauges' "
                       f"signs and axes and the load column, or fit with --robust", key="C_F")
    raised = _raise_unmeasured(C, m, u)
    names = ", ".join(f"c_{'xyz'[i]}{'xyz'[i]}" for i in u)
    note = (f"{names} not measured (no load along {', '.join('xyz'[i] for i in u)}): {guess_is} "
            f"({', '.join(f'{guess[i, i]:.4g}' for i in u)} mm/N) is too small for the measured entries (a joint "
            f"or bond softer than simulated?); raised to the smallest value they allow "
            f"({', '.join(f'{raised[i, i]:.4g}' for i in u)} mm/N): a lower bound. Record a load along "
            f"{', '.join('xyz'[i] for i in u)} to measure it")
    return raised, [note]


def _filled(measured: np.ndarray, guess: np.ndarray) -> np.ndarray:
    C = np.array(guess, dtype=float)
    for i in range(3):
        for j in range(3):
            a, b = measured[i, j], measured[j, i]
            if np.isfinite(a) and np.isfinite(b):
                C[i, j] = 0.5 * (a + b)
            elif np.isfinite(a):
                C[i, j] = C[j, i] = a
            elif np.isfinite(b):
                C[i, j] = C[j, i] = b
    return C


def _is_psd(C: np.ndarray) -> bool:
    w = np.linalg.eigvalsh(0.5 * (C + C.T))
    return bool(w.min() >= -1e-9 * max(abs(w).max(), 1e-300))


def _raise_unmeasured(C: np.ndarray, m: np.ndarray, u: np.ndarray) -> np.ndarray:
    """``C`` with its unmeasured block ``C_uu`` raised by the least multiple of the identity that makes the Schur
    complement ``C_uu - C_um C_mm^+ C_mu`` positive semi-definite (plus :data:`_MARGIN` of the diagonal)."""
    out = C.copy()
    S = C[np.ix_(u, u)] - C[np.ix_(u, m)] @ np.linalg.pinv(C[np.ix_(m, m)]) @ C[np.ix_(m, u)]
    lift = max(0.0, -float(np.linalg.eigvalsh(0.5 * (S + S.T)).min()))
    out[np.ix_(u, u)] += np.eye(u.size) * lift
    out[u, u] *= 1.0 + _MARGIN
    return out
