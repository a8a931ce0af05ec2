"""calibrate: the MultiCal calibrator (robot model, identification, rod-deflection compensation, validation).

Uses compliance files from the FEA and the rig (the core's :class:`rodlab.RodCompliance`), never their code.
"""
from .campaign import Campaign, Fixture, read_campaign, read_fixture, write_fixture
from .points_file import PointSet, read_points
from .device import Device, Sensor, read_device, write_device
from .probe import FixtureFit, ProbeSet, fit_fixture, read_probe
from .readings import apply_device, far_points
from .compensations import COMPENSATIONS, Compensation, RodDeflection, ThermalGrowth, deflection_offsets
from .errors import CalibrationError
from .estimate import FitOptions
from .identify import Observations, campaign_observations, identify, register_base_and_tool
from .kinematics import ModelParams, ball_positions
from .result import CalibrationResult, calibrated_params, read_calibration, result_dict, write_result
from .robot import Robot, robot_from_chain
from .rod import Rod
from .robot_formats import ROBOT_READERS, builtin_robots, read_robot, resolve_robot, robot_path
from .socket_check import SocketCheck, check_sockets
from .socket_fit import SocketFit, identify_sockets
from .sockets import SocketDistance, SocketReadings, read_sockets, write_sockets
from .validate import ErrorStats, validate
from rodlab.core.lazy import lazy_exports

__all__ = ["CampaignSpec", "simulate_campaign", "standard_fixture", "Priors",
           "Campaign", "Fixture", "PointSet", "read_campaign", "read_fixture", "read_points", "write_fixture",
           "Device", "Sensor", "read_device", "write_device", "apply_device", "far_points",
           "FixtureFit", "ProbeSet", "fit_fixture", "read_probe", "CalibrationError",
           "Rod", "FitOptions", "COMPENSATIONS", "Compensation", "RodDeflection", "deflection_offsets", "ThermalGrowth",
           "CalibrationResult", "Observations", "campaign_observations", "identify", "register_base_and_tool",
           "ModelParams", "ball_positions",
           "result_dict", "write_result", "read_calibration", "calibrated_params",
           "Robot", "robot_from_chain", "ROBOT_READERS", "builtin_robots", "read_robot",
           "resolve_robot", "robot_path", "ErrorStats", "validate", "SocketCheck", "check_sockets", "SocketFit",
           "identify_sockets", "SocketDistance", "SocketReadings", "read_sockets", "write_sockets"]

#: loaded on first use (simulation and prediction: ~30 ms of imports most commands do not need)
_LAZY = {"CampaignSpec": "simulate", "simulate_campaign": "simulate", "standard_fixture": "simulate",
         "Priors": "predict"}
__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())
