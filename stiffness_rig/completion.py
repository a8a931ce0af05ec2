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
    messages. Raises :class:`RigError` where no raise of the unmeasured diagonal makes it a compliance."""
    C = _filled(measured, guess)
    if _is_psd(C):
        return C, []
    seen = np.isfinite(np.diag(measured))
    m, u = np.nonzero(seen)[0], np.nonzero(~seen)[0]
    if u.size == 0 or m.size == 0 or not _is_psd(C[np.ix_(m, m)]):
        raise _contradiction(C, source)
    raised = _raise_unmeasured(C, m, u)
    if not _is_psd(raised):
        raise _contradiction(C, source)
    changed = [i for i in u if raised[i, i] != C[i, i]]
    axes = ", ".join("xyz"[i] for i in changed)
    note = (f"{', '.join(f'c_{a}{a}' for a in axes.split(', '))} not measured (no load along {axes}): {guess_is} "
            f"({', '.join(f'{guess[i, i]:.4g}' for i in changed)} mm/N) is too small for the measured entries (a "
            f"joint or bond softer than simulated?); raised to the least the measured entries allow "
            f"({', '.join(f'{raised[i, i]:.4g}' for i in changed)} mm/N): a lower bound. Record a load along "
            f"{axes} to measure it")
    return raised, [note]


def _contradiction(C: np.ndarray, source: str) -> RigError:
    where = f"{source}: " if source else ""
    return RigError(f"{where}the measured compliance entries contradict one another (C_F is not positive "
                    f"semi-definite: eigenvalues {np.linalg.eigvalsh(0.5 * (C + C.T))}); check the gauges' signs "
                    f"and axes and the load column", key="C_F")


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
    """``C`` with its unmeasured block ``C_uu`` raised along the directions where the Schur complement
    ``S = C_uu - C_um C_mm^+ C_mu`` is negative, by just that much (``C_uu += V max(-L, 0) V^T`` of ``S = V L V^T``,
    plus :data:`_MARGIN` of the lift): an unmeasured entry the measured ones do not constrain is not changed."""
    out = C.copy()
    S = C[np.ix_(u, u)] - C[np.ix_(u, m)] @ np.linalg.pinv(C[np.ix_(m, m)]) @ C[np.ix_(m, u)]
    lam, V = np.linalg.eigh(0.5 * (S + S.T))
    lift = (V * np.maximum(-lam, 0.0)) @ V.T
    out[np.ix_(u, u)] += lift * (1.0 + _MARGIN)
    return out
