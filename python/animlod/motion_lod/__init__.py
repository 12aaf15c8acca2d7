"""Motion level of detail (seeds/000): analysis, frozen joints, re-fit and level chains."""

from .analysis import MotionAnalysis, analyze_motion

__all__ = ["MotionAnalysis", "analyze_motion"]
