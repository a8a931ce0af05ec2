"""stiffness_rig: acquisition from the stiffness rig, its simulator, load-deflection fitting, r_rod.

Needs only the core install (numpy, scipy, matplotlib, pyserial, minimalmodbus): a rig PC does not need the
CAD stack.
"""
from .errors import DeviceError, RigError
from .fit import LineFit, NoLoadResponse, RigFit, fit_recording
from .holds import Holds, hold_averages
from .instrument_profile import InstrumentProfile
from .instruments import RigClient
from .load import LoadCheck, measured_load
from .plan_check import default_masses, linear_range_warnings
from .plot import plot_fit
from .recording import FORMAT_RIG, RecordingWriter, RigRecording, read_recording

__all__ = ["RigError", "DeviceError", "LineFit", "NoLoadResponse", "RigFit", "fit_recording", "Holds", "hold_averages",
           "plot_fit", "FORMAT_RIG", "RecordingWriter", "RigRecording", "read_recording", "InstrumentProfile", "RigClient",
           "LoadCheck", "measured_load", "default_masses", "linear_range_warnings"]
