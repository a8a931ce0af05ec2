"""Elasticity tensors: isotropic and transversely isotropic (about the local tube axis), per element.

Transversely isotropic carbon (axis 1 = fibre = tube axis): E1 = ``E_GPa``, E2 = E3 = ``E_transverse_GPa``,
nu12 = nu13 = ``nu``, G12 = G13 = ``G_GPa`` (the axial shear modulus: it sets the torsion of a tube and its
transverse shear), nu23 = ``NU23_DEFAULT`` (0.4, typical of carbon-epoxy; it only affects in-plane
deformation of the wall), G23 = E2 / (2 (1 + nu23)). Units: N/mm^2.
"""
from __future__ import annotations

import numpy as np

from rodlab.core.materials import Material
from rodlab.core.units import gpa_to_mpa

__all__ = ["stiffness_tensor_local", "rotate_tensor", "element_tensors", "NU23_DEFAULT"]

NU23_DEFAULT = 0.4
_VOIGT = {(0, 0): 0, (1, 1): 1, (2, 2): 2, (1, 2): 3, (2, 1): 3, (0, 2): 4, (2, 0): 4, (0, 1): 5, (1, 0): 5}


def _voigt_to_tensor(C6: np.ndarray) -> np.ndarray:
    C = np.empty((3, 3, 3, 3))
    for (i, j), I in _VOIGT.items():
        for (k, l), J in _VOIGT.items():
            C[i, j, k, l] = C6[I, J]
    return C


def stiffness_tensor_local(mat: Material) -> np.ndarray:
    """4th-order stiffness [N/mm^2], shape=(3, 3, 3, 3), with axis 0 along the tube axis."""
    E1 = gpa_to_mpa(mat.E_GPa)
    if mat.is_isotropic:
        lam = E1 * mat.nu / ((1 + mat.nu) * (1 - 2 * mat.nu))
        mu = E1 / (2 * (1 + mat.nu))
        d = np.eye(3)
        return (lam * np.einsum("ij,kl->ijkl", d, d)
                + mu * (np.einsum("ik,jl->ijkl", d, d) + np.einsum("il,jk->ijkl", d, d)))
    E2 = gpa_to_mpa(mat.E_t_GPa)
    G12 = gpa_to_mpa(mat.G_axial_GPa)
    n12, n23 = mat.nu, NU23_DEFAULT
    G23 = E2 / (2 * (1 + n23))
    S = np.zeros((6, 6))
    S[0, 0] = 1 / E1
    S[1, 1] = S[2, 2] = 1 / E2
    S[0, 1] = S[1, 0] = S[0, 2] = S[2, 0] = -n12 / E1
    S[1, 2] = S[2, 1] = -n23 / E2
    S[3, 3] = 1 / G23
    S[4, 4] = S[5, 5] = 1 / G12
    return _voigt_to_tensor(np.linalg.inv(S))


def local_frames(axes: np.ndarray) -> np.ndarray:
    """Rotation matrices, shape=(n, 3, 3), whose first column is the unit axis."""
    a = axes / np.linalg.norm(axes, axis=1, keepdims=True)
    helper = np.where(np.abs(a[:, [0]]) < 0.9, np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]]))
    b = np.cross(a, helper)
    b /= np.linalg.norm(b, axis=1, keepdims=True)
    c = np.cross(a, b)
    return np.stack([a, b, c], axis=2)


def rotate_tensor(C: np.ndarray, R: np.ndarray) -> np.ndarray:
    """``C'_ijkl = R_ip R_jq R_kr R_ls C_pqrs`` for rotations R, shape=(n, 3, 3) -> (n, 3, 3, 3, 3)."""
    return np.einsum("nip,njq,nkr,nls,pqrs->nijkl", R, R, R, R, C, optimize=True)


def element_tensors(materials: list[Material], part_index: np.ndarray, tube_axis: np.ndarray) -> np.ndarray:
    """Stiffness tensor of every element, shape=(n_elements, 3, 3, 3, 3) [N/mm^2]."""
    n = part_index.size
    out = np.empty((n, 3, 3, 3, 3))
    for k, mat in enumerate(materials):
        sel = np.nonzero(part_index == k)[0]
        if sel.size == 0:
            continue
        C = stiffness_tensor_local(mat)
        if mat.is_isotropic:
            out[sel] = C
        else:
            out[sel] = rotate_tensor(C, local_frames(tube_axis[sel]))
    return out
