"""Level of detail for animated faces (seeds/004: Lee, Kalra, Magnenat-Thalmann et al.).

Region-animated faces (the paper's model):

- :mod:`.regions`: region labels, region groups and their importance weights;
- :mod:`.lattice`: region lattices, rational FFD and 2x2x2 fits (evaluated in the C++ core);
- :mod:`.mpa`: Minimum Perceptible Actions, expressions, MPA animations;
- :mod:`.rig`: the face with lattices and MPAs, and the per-level runtime animator;
- :mod:`.active_tree`: the regions animated at each level;
- :mod:`.chain`: geometry levels (AQEM with region importance), animation floors, lattice reduction;
- :mod:`.selection`: levels and frame skipping from the view;
- :mod:`.measure`: Table 1 (sizes, time per frame, surface error);
- :mod:`.procedural`: the procedural head of :mod:`animlod.synth` rigged.

Blendshape faces (glTF morph targets, or a neutral face and expressions):
:mod:`.blendshape` (ranking, pruning, simplification with targets carried), :mod:`.sources`
(pose folders) and :mod:`.lod_glb` (glTF faces through the whole-document pipeline, and every
face's levels as one LoD GLB). Faces without region labels: :mod:`.grow` (regions from motion).
Pictures: :mod:`.plots`. The whole job for the command line: :mod:`.pipeline`.
"""

from .active_tree import ActiveTree
from .blendshape import BlendshapeFace, BlendshapeLodOptions, build_blendshape_lod, rank_targets
from .chain import FaceLodChain, FaceLodOptions, build_face_lod
from .grow import GrowOptions, grow_regions
from .mpa import Expression, Mpa, MpaAnimation, expression_sequence
from .procedural import procedural_face
from .regions import FaceRegions, RegionGroup
from .rig import FaceRig, LevelAnimator
from .selection import Camera, select_face_levels

__all__ = [
    "ActiveTree",
    "BlendshapeFace",
    "BlendshapeLodOptions",
    "Camera",
    "Expression",
    "FaceLodChain",
    "FaceLodOptions",
    "FaceRegions",
    "FaceRig",
    "GrowOptions",
    "LevelAnimator",
    "Mpa",
    "MpaAnimation",
    "RegionGroup",
    "build_blendshape_lod",
    "build_face_lod",
    "expression_sequence",
    "grow_regions",
    "procedural_face",
    "rank_targets",
    "select_face_levels",
]
