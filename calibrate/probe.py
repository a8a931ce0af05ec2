"""The fixture's clamping poses from probing (``*.probe.csv``, ``rodlab.probe/1``).

A measuring arm or laser tracker measures the device's reference features (``features_D_mm`` of its device
file: the fast-lock's pin and balls) at every clamping position, in the instrument's own frame {A}. Each
position's device frame is the least-squares rigid fit of the features' coordinates in {D} onto the probed
points (Kabsch), its covariance ``sigma^2 (J^T J)^-1`` from the instrument's stated accuracy sigma (per
coordinate, 1 sigma; ``# accuracy_mm:``). Every pose is then expressed in {W} = {D_world}: ``T_W_Dj =
T_A_Dw^-1 T_A_Dj``, its covariance propagated from both fits (the world fit's error is shared by all positions;
that correlation between positions is not kept). A position whose residuals exceed the accuracy (chi-square
test) is flagged with its suspect feature (the one whose leave-one-out fit of the others fits best): a feature
misprobed or the device seated wrong. With 4 features a probe error that keeps the point's distances to two
others is ambiguous between two features; the flag itself is not.
"""
from __future__ import annotations

import csv
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rodlab.core.errors import did_you_mean
from rodlab.core.fileio import read_text_checked
from rodlab.core.frames import matrix_to_pose, skew, pose_to_matrix

from .campaign import Fixture, cell_number, leading_comments
from .device import Device
from .errors import CalibrationError

__all__ = ["ProbeSet", "PositionFit", "FixtureFit", "read_probe", "fit_fixture", "FLAG_P"]

#: a position whose residuals' chi-square has a p-value below this is flagged
FLAG_P = 1e-3
#: the coarsest accuracy per coordinate a probing instrument states [mm] (a CMM's 0.001-0.005, a tracker's or an
#: arm's 0.01-0.1): beyond, the number is in um
MAX_ACCURACY_MM = 1.0
#: the probe file's distances between features over the device file's: within these, the same unit and device
DISTANCE_RATIO = (0.5, 2.0)
PROBE_COLUMNS = ("position", "feature", "x_mm", "y_mm", "z_mm")


@dataclass
class ProbeSet:
    """Probed features: position (N,), feature (N,) names, x_A_mm (N, 3) in the instrument frame [mm],
    accuracy_mm the instrument's accuracy per coordinate (1 sigma) [mm], lines (N,) of the file."""

    position: np.ndarray
    feature: list
    x_A_mm: np.ndarray
    accuracy_mm: float
    path: Path | None = None
    lines: np.ndarray = field(default_factory=lambda: np.zeros(0, int))

    def __post_init__(self):
        n = len(self.feature)
        if np.shape(self.position) != (n,) or np.shape(self.x_A_mm) != (n, 3):
            raise ValueError(f"position (N,) and x_A_mm (N, 3) must match the {n} features")
        if not self.accuracy_mm > 0:
            raise ValueError(f"accuracy_mm must be > 0, got {self.accuracy_mm}")


def read_probe(path) -> ProbeSet:
    """Read a probe file; errors name the file, line and column."""
    p = Path(path)
    text = read_text_checked(p, CalibrationError)
    meta = {key: (k, val) for k, key, val in leading_comments(text)}
    if "accuracy_mm" not in meta:
        near = [key for key in meta if did_you_mean(key, ["accuracy_mm"], units=True)]
        if near:                                  # a typo in the key: name the line it is on
            k = meta[near[0]][0]
            raise CalibrationError(f"unknown comment key '# {near[0]}:'{did_you_mean(near[0], ['accuracy_mm'], units=True)} (the "
                                   "instrument's accuracy per coordinate, 1 sigma [mm])", path=p, line=k, key=near[0])
        raise CalibrationError("missing comment line '# accuracy_mm: ...' (the instrument's accuracy per coordinate,"
                               " 1 sigma [mm]) before the header", path=p, line=1, key="accuracy_mm")
    k, val = meta["accuracy_mm"]
    acc = cell_number(val, p, k, "accuracy_mm")
    if not acc > 0:
        raise CalibrationError(f"expected an accuracy > 0 [mm], got {val!r}", path=p, line=k, key="accuracy_mm")
    if acc > MAX_ACCURACY_MM:            # a device trial: 5 (meant um) had made every pose uncertain by 10-17 mm
        raise CalibrationError(f"an accuracy of {acc:g} mm per coordinate is no probing instrument's (a CMM's "
                               f"0.001-0.005 mm, an arm's or a tracker's 0.01-0.1 mm): if it is in um, write "
                               f"{acc / 1000:g}", path=p, line=k, key="accuracy_mm")
    lines = text.splitlines()
    i = next((n for n, ln in enumerate(lines) if ln.strip() and not ln.lstrip().startswith("#")), None)
    if i is None:
        raise CalibrationError("no header line", path=p)
    header = [h.strip() for h in next(csv.reader([lines[i]]))]
    if header != list(PROBE_COLUMNS):
        raise CalibrationError(f"expected the header {','.join(PROBE_COLUMNS)}, got {','.join(header)}", path=p,
                               line=i + 1)
    pos, feat, x, ln, seen = [], [], [], [], {}
    for k, row in enumerate(csv.reader(lines[i + 1:]), start=i + 2):
        if not row or not "".join(row).strip() or row[0].lstrip().startswith("#"):
            continue
        if len(row) != 5:
            raise CalibrationError(f"expected 5 cells, got {len(row)}", path=p, line=k)
        j = cell_number(row[0], p, k, "position")
        if j != int(j) or j < 1:
            raise CalibrationError(f"expected a positive integer, got {row[0]!r}", path=p, line=k, key="position")
        name = row[1].strip()
        if not name:
            raise CalibrationError("empty feature name", path=p, line=k, key="feature")
        if (int(j), name) in seen:
            raise CalibrationError(f"feature {name!r} of position {int(j)} appears twice (also on line "
                                   f"{seen[(int(j), name)]})", path=p, line=k, key="feature")
        seen[(int(j), name)] = k
        pos.append(int(j))
        feat.append(name)
        x.append([cell_number(c, p, k, col) for c, col in zip(row[2:], PROBE_COLUMNS[2:])])
        ln.append(k)
    if not pos:
        raise CalibrationError("no data rows", path=p, line=i + 1)
    return ProbeSet(np.array(pos), feat, np.array(x), acc, p, np.array(ln))



@dataclass
class PositionFit:
    """One clamping position's fit: T_A_D (4, 4) device frame in the instrument frame, cov_A (6, 6) of its
    left perturbation (translation [mm], rotation vector [rad] in {A}), residuals_mm (k, 3) per feature,
    features (k,) names, chi2 over dof = 3k - 6, p its p-value, flagged (p < FLAG_P); suspect (feature, how far
    [mm] its probe lies from the fit of the others) the feature whose removal leaves the best fit (with 4 or
    more features; else the largest residual); swapped (feature, feature) two labels that, exchanged, make the fit
    agree with the accuracy, else None."""

    position: int
    T_A_D: np.ndarray
    cov_A: np.ndarray
    residuals_mm: np.ndarray
    features: list
    chi2: float
    dof: int
    p: float
    suspect: tuple = ("", 0.0)
    swapped: tuple | None = None

    @property
    def flagged(self) -> bool:
        return self.p < FLAG_P

    @property
    def rms_mm(self) -> float:
        """rms residual per coordinate [mm]."""
        return float(np.sqrt(np.mean(self.residuals_mm ** 2)))



@dataclass
class FixtureFit:
    """The fixture fitted from probes (``fixture``: poses in {W} with their covariance) and each position's fit."""

    fixture: Fixture
    fits: dict
    accuracy_mm: float

    @property
    def flagged(self) -> list:
        return [f for f in self.fits.values() if f.flagged]

    def sigmas(self, j: int) -> np.ndarray:
        """shape=(6,): standard uncertainties of pose j [mm, deg] (zeros for the world position)."""
        C = self.fixture.pose_cov.get(j) if self.fixture.pose_cov else None
        return np.zeros(6) if C is None else np.sqrt(np.diag(C))


def fit_fixture(probes: ProbeSet, device: Device, world_position: int, contact_force_N=None) -> FixtureFit:
    """Each probed position's device frame fitted to its features, expressed in {W} = {D_world_position} with
    its covariance; ``contact_force_N`` (3,) [N] in {D} for the fixture file (default: the device's springs'
    at the datum, else the paper's)."""
    if not device.features_D_mm:
        raise CalibrationError("the device file lists no reference features (features_D_mm): add the coordinates "
                               "in {D} of the points the arm probes", path=device.path, key="features_D_mm")
    _check_features(probes, device)
    _check_scale(probes, device)
    fits = {int(j): _fit_position(probes, device, int(j)) for j in np.unique(probes.position)}
    if world_position not in fits:
        raise CalibrationError(f"--world-position {world_position} was not probed (positions {sorted(fits)})",
                               path=probes.path, key="position")
    Tw, Cw = fits[world_position].T_A_D, fits[world_position].cov_A
    poses, covs = {}, {}
    for j, f in fits.items():
        if j == world_position:
            poses[j] = np.zeros(6)
            continue
        poses[j] = matrix_to_pose(np.linalg.inv(Tw) @ f.T_A_D)
        covs[j] = _pose_covariance(Tw, Cw, f.T_A_D, f.cov_A)
    if contact_force_N is None:
        contact_force_N = (device.force_D(device.zero_mm[None, :])[0] if device.has_springs
                           else np.array([1.10, 1.25, 1.05]))
    probing = {"accuracy_mm": probes.accuracy_mm, "probe_file": str(probes.path) if probes.path else None,
               "device": device.name,
               "rms_residual_mm": {str(j): round(f.rms_mm, 6) for j, f in fits.items()},
               "flagged": {str(f.position): f"{f.suspect[0]} {f.suspect[1]:.4f} mm off" for f in fits.values()
                           if f.flagged}}
    fix = Fixture(poses, np.asarray(contact_force_N, float), world_position, None, covs, probing)
    return FixtureFit(fix, fits, probes.accuracy_mm)


def _check_features(probes: ProbeSet, device: Device) -> None:
    known = list(device.features_D_mm)
    for name, line in zip(probes.feature, probes.lines):
        if name not in device.features_D_mm:
            raise CalibrationError(f"feature {name!r} is not in the device file's features_D_mm {known}."
                                   + did_you_mean(name, known), path=probes.path, line=int(line), key="feature")


def _check_scale(probes: ProbeSet, device: Device) -> None:
    """Refuse a probe file whose distances between features are not the device file's (outside
    :data:`DISTANCE_RATIO`): metres, um or inches, or another device (a device trial: a probe file in metres had
    been fitted, every position flagged, and written)."""
    ratios = []
    for j in np.unique(probes.position):
        m = np.nonzero(probes.position == j)[0]
        if m.size < 2:
            continue
        F = np.array([device.features_D_mm[probes.feature[i]] for i in m])
        P = probes.x_A_mm[m]
        spread_F = np.linalg.norm(F - F.mean(0))
        if spread_F > 0:
            ratios.append(np.linalg.norm(P - P.mean(0)) / spread_F)
    if not ratios:
        return
    r = float(np.median(ratios))
    if DISTANCE_RATIO[0] <= r <= DISTANCE_RATIO[1]:
        return
    _check_device_scale(device, r)
    unit = min(((0.001, "in metres: multiply x_mm, y_mm, z_mm by 1000"), (1000.0, "in um: divide them by 1000"),
                (1 / 25.4, "in inches: multiply them by 25.4")), key=lambda u: abs(np.log(r / u[0])))
    cause = unit[1] if abs(np.log(r / unit[0])) < np.log(1.5) else "not those of this device file's features"
    raise CalibrationError(f"the probed features lie {r:.4g} x as far apart as the device file's features_D_mm "
                           f"({device.path or device.name}): the coordinates are {cause}", path=probes.path,
                           key="x_mm")


#: the span of a device's features [mm] a device file in mm can have (a MultiCal's balls and nests lie tens of mm
#: apart); outside it the device file is the one in other units
FEATURE_SPAN_MM = (2.0, 5000.0)


def _check_device_scale(device: Device, ratio: float) -> None:
    """Blame the device file, not the probe file, where its own features span no plausible size in mm (review: a
    device file in metres had been reported as a probe file in um)."""
    F = np.array(list(device.features_D_mm.values()), float)
    span = float(np.max(np.linalg.norm(F[:, None] - F[None], axis=-1)))
    if FEATURE_SPAN_MM[0] <= span <= FEATURE_SPAN_MM[1]:
        return
    unit = "metres (multiply them by 1000)" if span < FEATURE_SPAN_MM[0] else "um (divide them by 1000)"
    raise CalibrationError(f"the device file's features_D_mm span {span:.4g} mm, the probed features lie {ratio:.4g} x "
                           f"as far apart: the device file's features look written in {unit}", path=device.path,
                           key="features_D_mm")


def _fit_position(probes: ProbeSet, device: Device, j: int) -> PositionFit:
    m = np.nonzero(probes.position == j)[0]
    names = [probes.feature[i] for i in m]
    F = np.array([device.features_D_mm[n] for n in names])
    P = probes.x_A_mm[m]
    if m.size < 3 or np.linalg.matrix_rank(F - F.mean(0), tol=1e-3 * max(1.0, np.abs(F).max())) < 2:
        raise CalibrationError(f"position {j}: {m.size} feature(s) {names} cannot fix the device frame; probe at "
                               f"least 3 features not in a line", path=probes.path, line=int(probes.lines[m[0]]),
                               key="feature")
    T = _kabsch(F, P)
    pA = F @ T[:3, :3].T + T[:3, 3]
    r = P - pA
    J = np.zeros((m.size, 3, 6))
    J[:, :, :3] = np.eye(3)
    J[:, :, 3:] = -skew(pA)                         # left perturbation: dp = dt + omega x p
    J = J.reshape(-1, 6)
    s2 = probes.accuracy_mm ** 2
    cov = s2 * np.linalg.inv(J.T @ J)
    chi2 = float((r ** 2).sum() / s2)
    dof = 3 * m.size - 6
    from scipy.stats import chi2 as chi2_dist                           # heavy (scipy.stats, ~0.6 s)
    p = float(chi2_dist.sf(chi2, dof)) if dof > 0 else 1.0
    swapped = _swapped_labels(F, P, names, s2, dof) if p < FLAG_P else None
    return PositionFit(j, T, cov, r, names, chi2, dof, p, _suspect(F, P, r, names), swapped)


def _swapped_labels(F: np.ndarray, P: np.ndarray, names: list, s2: float, dof: int) -> tuple | None:
    """Two features whose labels, exchanged, make the position's fit agree with the instrument's accuracy (a device
    trial: ``ball_2`` and ``ball_3`` swapped had been 90 mm off and sent to be probed again); None otherwise."""
    from scipy.stats import chi2 as chi2_dist                           # heavy (scipy.stats, ~0.6 s)
    best = None
    for a in range(len(names)):
        for b in range(a + 1, len(names)):
            order = np.arange(len(names))
            order[[a, b]] = order[[b, a]]
            T = _kabsch(F[order], P)
            chi2 = float(((P - F[order] @ T[:3, :3].T - T[:3, 3]) ** 2).sum() / s2)
            if best is None or chi2 < best[0]:
                best = (chi2, names[a], names[b])
    if best is None or dof <= 0 or chi2_dist.sf(best[0], dof) < FLAG_P:
        return None
    return best[1], best[2]


def _suspect(F: np.ndarray, P: np.ndarray, r: np.ndarray, names: list) -> tuple:
    """The feature most likely misprobed: the one whose leave-one-out fit of the others leaves the smallest
    sum of squares (its own distance from that fit [mm]); with 3 features, the largest residual."""
    if len(names) < 4:
        d = np.linalg.norm(r, axis=1)
        return names[int(np.argmax(d))], float(d.max())
    best = None
    for i in range(len(names)):
        keep = np.arange(len(names)) != i
        T = _kabsch(F[keep], P[keep])
        rest = float(((P[keep] - F[keep] @ T[:3, :3].T - T[:3, 3]) ** 2).sum())
        off = float(np.linalg.norm(P[i] - T[:3, :3] @ F[i] - T[:3, 3]))
        if best is None or rest < best[0]:
            best = (rest, names[i], off)
    return best[1], best[2]


def _kabsch(F: np.ndarray, P: np.ndarray) -> np.ndarray:
    """4x4 rigid transform T minimising sum |R F_i + t - P_i|^2."""
    fc, pc = F.mean(0), P.mean(0)
    U, _, Vt = np.linalg.svd((F - fc).T @ (P - pc))
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
    R = Vt.T @ D @ U.T
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, pc - R @ fc
    return T


def _perturbed(T: np.ndarray, e: np.ndarray) -> np.ndarray:
    """T moved by the left perturbation e = (dt [mm], omega [rad]) (exact rotation)."""
    from scipy.spatial.transform import Rotation                        # heavy (scipy.spatial, ~0.35 s)
    E = np.eye(4)
    E[:3, :3] = Rotation.from_rotvec(e[3:]).as_matrix()
    E[:3, 3] = e[:3]
    return E @ T


def _pose_covariance(Tw, Cw, Tj, Cj, h: float = 1e-6) -> np.ndarray:
    """Covariance (6, 6) of the pose [x, y, z, a, b, c] (mm, deg) of T_W_Dj = Tw^-1 Tj from the fits' own
    (central differences over both perturbations)."""
    def pose(ew, ej):
        return matrix_to_pose(np.linalg.inv(_perturbed(Tw, ew)) @ _perturbed(Tj, ej))
    J = np.zeros((6, 12))
    for k in range(12):
        e = np.zeros(12)
        e[k] = h
        d = pose(e[:6], e[6:]) - pose(-e[:6], -e[6:])
        d[3:] = (d[3:] + 180.0) % 360.0 - 180.0              # angles wrap
        J[:, k] = d / (2 * h)
    C = np.zeros((12, 12))
    C[:6, :6], C[6:, 6:] = Cw, Cj
    out = J @ C @ J.T
    return (out + out.T) / 2


#: where the simulated measuring arm stands: its frame {A} in {W} [mm, deg]
ARM_POSE_W = np.array([900.0, -400.0, -300.0, 5.0, -10.0, 120.0])


def simulated_probe_text(Ts: dict, device: Device, accuracy_mm: float, rng, arm_pose_W=ARM_POSE_W) -> str:
    """A probe file of the device frames ``Ts`` {j: 4x4 pose of {D_j} in {W}}: every feature measured in the
    arm's frame (at ``arm_pose_W``) with normal errors of ``accuracy_mm`` per coordinate."""
    T_A_W = np.linalg.inv(pose_to_matrix(arm_pose_W))
    rows = [f"# accuracy_mm: {accuracy_mm:g}", ",".join(PROBE_COLUMNS)]
    for j in sorted(Ts):
        T = T_A_W @ Ts[j]
        for name, f in device.features_D_mm.items():
            x = T[:3, :3] @ f + T[:3, 3] + rng.normal(0, accuracy_mm, 3)
            rows.append(f"{j},{name}," + ",".join(f"{v:.4f}" for v in x))
    return "\n".join(rows) + "\n"
