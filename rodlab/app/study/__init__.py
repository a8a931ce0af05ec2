"""rodlab study: from a rod design to the calibration accuracy it will give on a robot (application layer).

Designs (an L1 x L2 grid, material and tube variants, or a list) -> compliance (joint-calibrated frame), mass,
c_rod, thermal growth, natural frequencies, strength margins -> pose planning on the robot (O1..O5) ->
Monte-Carlo campaigns calibrated with every compensation method -> predicted accuracy with its band and
error budget, Pareto fronts, heat maps, a recommendation.
"""
from .designs import Candidate, grid_candidates, list_candidates, r_prior_of
from .prepare import DesignSetup, prepare_design
from .run import StudyRun, StudySpec, run_study
from .table import STUDY_COLUMNS, Recommendation, recommend, study_table
from .outputs import StudyOutputs, best_method, write_study_outputs
from .design_warnings import DesignWarning, study_warnings

__all__ = ["Candidate", "grid_candidates", "list_candidates", "r_prior_of", "DesignSetup", "prepare_design",
           "StudyRun", "StudySpec", "run_study", "STUDY_COLUMNS", "Recommendation", "recommend", "study_table",
           "StudyOutputs", "best_method", "write_study_outputs", "DesignWarning", "study_warnings"]
