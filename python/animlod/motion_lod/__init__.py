"""Motion level of detail (seeds/000): analysis, frozen joints, re-fit and level chains.

Start with :func:`build_motion_chain` (or ``animlod motion`` on the command line); the pieces:
analysis.py (Eqs. 1-3), frozen.py (Section 5.1), objective.py (Eqs. 4-8), refit.py (SLSQP),
newton.py (the faster solver of the same objective), grouped_solve.py (how both cut and run the
work), skeleton_reduce.py, skin_transfer.py, chain.py, plots.py.
"""

from .analysis import MotionAnalysis, analyze_motion
from .chain import LevelReport, MotionLevel, MotionLodChain, build_motion_chain, level_joint_counts
from .grouped_solve import FrameFailure
from .objective import Weights
from .refit import SlsqpOptions

__all__ = [
    "FrameFailure",
    "LevelReport",
    "MotionAnalysis",
    "MotionLevel",
    "MotionLodChain",
    "SlsqpOptions",
    "Weights",
    "analyze_motion",
    "build_motion_chain",
    "level_joint_counts",
]
