"""animlod: level of detail for animated content.

The data model lives in :mod:`animlod.model`; file formats in :mod:`animlod.io`; procedural
assets in :mod:`animlod.synth`. Heavy lifting is done by the C++ core, ``animlod._core``.
"""

from .aqem import motion_features, simplify_animated, simplify_skinned
from .model import AnimatedMesh, LodChain, LodLevel, Motion, Skeleton, SkinnedMesh
from .motion_lod import analyze_motion, build_motion_chain
from .options import AqemOptions, MotionFeatureOptions, TdagOptions
from .tdag import TemporalDag
from .threads import set_thread_limit, thread_limit

__version__ = "0.1.0"

__all__ = [
    "AnimatedMesh",
    "AqemOptions",
    "LodChain",
    "LodLevel",
    "Motion",
    "MotionFeatureOptions",
    "Skeleton",
    "SkinnedMesh",
    "TdagOptions",
    "TemporalDag",
    "__version__",
    "analyze_motion",
    "build_motion_chain",
    "motion_features",
    "set_thread_limit",
    "simplify_animated",
    "simplify_skinned",
    "thread_limit",
]
