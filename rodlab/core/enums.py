"""Conventions of the rodlab contract as Enums (never bare strings in the API).

The effect IDs are not listed here: the rig effects' ``RigEffect`` (:mod:`rodlab.stiffness_rig.effects`) and the
campaign effects' ``CampaignEffect`` (:mod:`rodlab.calibrate.effects`) are built by their registries from the
effect modules they find (:func:`id_enum`), so that a new effect is one module; the core may not import them.
"""
from __future__ import annotations

from enum import Enum
from functools import lru_cache

from .errors import RodlabError, did_you_mean

__all__ = ["Method", "Part", "LoadAxis", "Phase", "DesignStatus", "Trial", "AccuracySource", "Completeness", "Verdict",
           "Subject", "FindingKind", "MODEL_FORM", "id_enum", "BendModel", "SegmentKind", "FeaModel", "SolverBackend",
           "LineProtocol", "Checksum", "ErrorEstimate", "StudyWarning"]


class _StrEnum(str, Enum):
    def __str__(self) -> str:  # prints as its contract spelling
        return str(self.value)

    @classmethod
    def parse(cls, value: "str | _StrEnum", what: str = "value"):
        """Parse the contract spelling; raise :class:`ValueError` listing the choices."""
        if isinstance(value, cls):
            return value
        try:
            return cls(str(value).strip().lower())
        except ValueError:
            choices = [m.value for m in cls]
            raise RodlabError(
                f"unknown {what} {value!r}; expected one of {choices}."
                + did_you_mean(str(value), choices)) from None


class Method(_StrEnum):
    """How a compliance file was obtained (contract ``method``)."""

    NONE = "none"   #: zero matrices: no rod-deflection compensation
    CALC = "calc"   #: closed form (Euler-Bernoulli frame), paper Eqs. 15/17
    FEA = "fea"     #: finite elements (solid or beam frame)
    MEAS = "meas"   #: stiffness-rig measurement of C_F, C_g = r_rod * C_g_sim (Eq. 22)


class Part(_StrEnum):
    """Named parts of a measuring rod (paper Fig. 3a), flange to ball."""

    PIPE_HOLDER = "pipe_holder"
    PIPE_I = "pipe_I"
    RING_1 = "ring_1"
    BEND = "bend"
    RING_2 = "ring_2"
    PIPE_II = "pipe_II"
    BALL_HOLDER = "ball_holder"
    BALL = "ball"

    @classmethod
    def parse(cls, value, what: str = "part"):
        if isinstance(value, cls):
            return value
        for m in cls:
            if m.value.lower() == str(value).strip().lower():
                return m
        return super().parse(value, what)


class LoadAxis(_StrEnum):
    """Tool-frame direction of a load on the stiffness rig (contract ``load_axis``)."""

    X = "x"
    Y = "y"
    Z = "z"
    NEG_X = "-x"
    NEG_Y = "-y"
    NEG_Z = "-z"

    @property
    def index(self) -> int:
        """Component index 0..2 of the axis."""
        return "xyz".index(self.value[-1])

    @property
    def sign(self) -> float:
        """+1 or -1."""
        return -1.0 if self.value.startswith("-") else 1.0


class Phase(_StrEnum):
    """Branch of a load series (contract ``phase``)."""

    LOAD = "load"
    UNLOAD = "unload"


class DesignStatus(_StrEnum):
    """What became of a design in a sweep or study (the ``status`` column)."""

    OK = "ok"
    INVALID = "invalid"          #: the design itself cannot be built (the message says why)
    UNREACHABLE = "unreachable"  #: the robot cannot use it (which clamping position, which limit)
    FAILED = "failed"            #: a computation failed (the message)


class StudyWarning(_StrEnum):
    """What a study says about a usable design's predicted accuracy beyond its numbers (``study.json`` ``warnings``)."""

    WORSE_THAN_NOMINAL = "worse_than_nominal"  #: the recommendation's method leaves the robot worse than uncalibrated
    SLIP_DOMINATES = "slip_dominates"          #: the rod's slip is most of the best method's error
    SLIP_EXTRAPOLATED = "slip_extrapolated"    #: the rod is far softer than the rods the slip was fitted on


class Trial(_StrEnum):
    """How one candidate model fares in a diagnoser's selection step (:mod:`rodlab.app.diagnose.search`)."""

    ACCEPT = "accept"        #: it passed the acceptance rule and is now the model
    NEXT = "next"            #: it failed a check that the next-ranked candidate may pass: try that one
    END_STEP = "end_step"    #: it failed in a way the lower-ranked candidates cannot mend: no model this step


class SimAccuracy(_StrEnum):
    """What a rig diagnosis takes the simulated compliance to be worth (``rodlab diagnose --sim-accuracy``)."""

    EXACT = "exact"          #: the simulation is the rod (a re-check against an earlier measurement of it)
    DESIGN = "design"        #: the design's tolerances plus the simulation method's own accuracy
    RELATIVE = "relative"    #: one relative standard deviation per C_F entry (no design known)


class FindingKind(_StrEnum):
    """Finding IDs of a diagnosis that name no modelled effect (contract ``effects.md``)."""

    #: rig: the linear difference from the simulation the tolerances explain (effects v2): nothing was left out,
    #: the rod as built differs from the simulated design
    MODEL_FORM = "model_form"
    #: both subjects: structure that no modelled effect explains, with where it is
    UNEXPLAINED = "unexplained"


#: the finding of a rig diagnosis whose linear difference from the simulation the tolerances explain (effects v2):
#: nothing was left out, the rod as built differs from the simulated design
MODEL_FORM = FindingKind.MODEL_FORM

def id_enum(name: str, values, *, module: str, doc: str) -> type:
    """A contract-spelling Enum (``str`` values, ``parse``, prints as its value) whose members are ``values`` in
    that order, each named by its upper-cased value: how a registry turns the IDs of the entries it found into
    its Enum (``RigEffect``, ``CampaignEffect``). ``module`` is where the registry keeps it (for pickling and
    the docs). The same IDs give back the very same class, so a registry that is rediscovered with the same
    modules keeps its members (``is`` still holds)."""
    values = tuple(str(v) for v in values)
    for v in values:
        if not (v.isidentifier() and v == v.lower()):
            raise ValueError(f"{name}: an ID must be a lower-case identifier (its contract spelling), got {v!r}")
    return _id_enum(name, values, module, doc)


@lru_cache(maxsize=None)
def _id_enum(name: str, values: tuple, module: str, doc: str) -> type:
    enum = _StrEnum(name, [(v.upper(), v) for v in values], module=module, qualname=name)
    enum.__doc__ = doc
    return enum


class Verdict(_StrEnum):
    """A diagnosis' verdict (contract ``rodlab.diagnosis/1``, ``verdict``)."""

    CONSISTENT = "consistent"      #: the recording matches the simulation within the noise: nothing found
    EXPLAINED = "explained"        #: the findings explain the difference down to the noise
    UNEXPLAINED = "unexplained"    #: structure above the noise is left that no modelled effect explains


class Subject(_StrEnum):
    """What a diagnosis looked at (contract ``rodlab.diagnosis/1``, ``subject``)."""

    RIG = "rig"              #: a stiffness-rig recording against a simulated compliance
    CAMPAIGN = "campaign"    #: a calibration campaign's residuals against the identified model


class AccuracySource(_StrEnum):
    """Where a calibration's predicted accuracy comes from (the *usable?* half of its verdict)."""

    VALIDATION = "validation"                #: a held-out validation set (``--validate``)
    CROSS_VALIDATION = "cross_validation"    #: k-fold cross-validation over the calibration's own points


class Completeness(_StrEnum):
    """Whether the identified model explains the readings down to the instrument's noise (the *complete?* half of
    a calibration's verdict; :mod:`calibrate.residual_test`)."""

    COMPLETE = "complete"        #: residuals consistent with the noise model
    NEARLY = "nearly"            #: significantly but only slightly above it (Birge ratio at most 1.5)
    INCOMPLETE = "incomplete"    #: the model leaves out errors well above the noise (a caution for a usable result)


class BendModel(str, Enum):
    """How the closed form treats the bend pipe."""

    ARC = "arc"        #: curved beam along the bend's arc (default; what the part is)
    CORNER = "corner"  #: two straight legs of the bend section meeting at the vertex (sharp-corner idealisation)


class SegmentKind(str, Enum):
    """The shape of a piece of a rod's centreline (:class:`rodlab.core.layout.Segment`)."""

    LINE = "line"
    ARC = "arc"


class ErrorEstimate(_StrEnum):
    """How the solid FEA estimates its discretisation error (``rodlab fea --error-estimate``)."""

    RECOVERY = "recovery"        #: stress recovery on the solve's own mesh (no second solve; the default)
    RICHARDSON = "richardson"    #: a second solve at 1.5 x the size, Richardson with an assumed order 3
    NONE = "none"                #: no estimate

    @property
    def describes(self) -> str:
        """What the estimate is, for help texts."""
        return {ErrorEstimate.RECOVERY: "Zienkiewicz-Zhu stress recovery on the solve's own mesh (no second solve)",
                ErrorEstimate.RICHARDSON: "a second mesh and solve at 1.5 x the size, Richardson with order 3",
                ErrorEstimate.NONE: "no estimate"}[self]


class FeaModel(str, Enum):
    """Which model computes the compliance."""

    SOLID = "solid"   #: 3-D elasticity, scikit-fem, curved P2 (reference)
    FRAME = "frame"   #: Timoshenko beam frame with pipe-bend flexibility (sweeps)
    CALC = "calc"     #: the paper's closed form generalised (Euler-Bernoulli frame)

    @property
    def describes(self) -> str:
        """What the model is, for help texts (``rodlab fea --help``)."""
        return _FEA_MODEL_TEXT[self]


_FEA_MODEL_TEXT = {
    FeaModel.SOLID: "3-D elasticity on the CAD mesh (scikit-fem, curved P2, transversely-isotropic carbon; needs the "
                    "cad extra)",
    FeaModel.FRAME: "Timoshenko beam frame with pipe-bend flexibility (fast)",
    FeaModel.CALC: "the closed form",
}


class SolverBackend(str, Enum):
    """Sparse direct solvers, fastest first."""

    PARDISO = "pardiso"   #: Intel MKL PARDISO (pypardiso + the mkl wheel)
    CHOLMOD = "cholmod"   #: SuiteSparse CHOLMOD (scikit-sparse + a system SuiteSparse)
    SUPERLU = "superlu"   #: SciPy's SuperLU (always there; the last fallback)


class LineProtocol(_StrEnum):
    """How a rig instrument sends its readings over its serial line (a rig profile's ``protocol``)."""

    QUERY = "query"      #: a request, answered by one line
    STREAM = "stream"    #: the instrument pushes lines by itself


class Checksum(_StrEnum):
    """A rig instrument's line checksum (a rig profile's ``checksum``)."""

    NONE = "none"        #: no checksum
    XOR = "xor"          #: the line ends with ``*HH``, the XOR of the bytes before ``*``
    SUM8 = "sum8"        #: the line ends with ``*HH``, the sum of the bytes before ``*`` modulo 256
