"""Motion level of detail (seeds/000): analysis, frozen joints, re-fit and level chains.

Start with :func:`build_motion_chain` (or ``animlod motion`` on the command line), or for a
skinned character :func:`build_skinned_motion_chain` (skin_measure.py: measured as the skin sees
it, as ``animlod character`` does); the pieces:
analysis.py (Eqs. 1-3), ranking.py (elimination orders), refit_choice.py (the default order,
chosen level by level by a trial re-fit), frozen.py (Section 5.1), objective.py
(Eqs. 4-8), core_refit.py (SLSQP in the C++ core, the default), refit.py (the same SLSQP in
Python, the reference), newton.py (damped Newton on the penalty objective), grouped_solve.py (how
the Python solvers cut and run the work), skeleton_reduce.py, skin_transfer.py, chain.py, plots.py.
"""

from .analysis import MotionAnalysis, analyze_motion
from .chain import (
    SOLVERS,
    JointFloor,
    LevelReport,
    MotionLevel,
    MotionLodChain,
    build_motion_chain,
    joint_floor,
    level_joint_counts,
)
from .grouped_solve import FrameFailure
from .objective import Weights
from .ranking import RANKINGS
from .skin_measure import build_skinned_motion_chain

__all__ = [
    "RANKINGS",
    "SOLVERS",
    "FrameFailure",
    "JointFloor",
    "LevelReport",
    "MotionAnalysis",
    "MotionLevel",
    "MotionLodChain",
    "Weights",
    "analyze_motion",
    "build_motion_chain",
    "build_skinned_motion_chain",
    "joint_floor",
    "level_joint_counts",
]
