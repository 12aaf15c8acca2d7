"""Pipelines: input files and options in, output files and a result record out.

The command line, ``make demo`` and the batch runner call these; they hold no argument parsing
and no printing.
"""

from .assets import character_asset, face_asset, simplify_asset
from .drawable_levels import DrawableSettings
from .lod_document import DocumentReport, simplify_document
from .motion import MotionReport, build_motion_levels, motion_asset
from .result import AssetResult, LevelRow

__all__ = [
    "AssetResult",
    "DocumentReport",
    "DrawableSettings",
    "LevelRow",
    "MotionReport",
    "build_motion_levels",
    "character_asset",
    "face_asset",
    "motion_asset",
    "simplify_asset",
    "simplify_document",
]
