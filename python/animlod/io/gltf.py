"""glTF 2.0 / GLB in and out: the public entry points.

Reading lives in :mod:`.gltf_read`, which builds on :mod:`.gltf_document` (checked buffers,
accessors, nodes and samplers), :mod:`.gltf_mesh` (primitives merged into one vertex set),
:mod:`.gltf_skin` (skins as skeletons, animations as motions) and :mod:`.gltf_keyframes`
(sampler interpolation). Writing lives in :mod:`.gltf_write` and :mod:`.glb_builder`; whole documents
with their levels (the LoD GLB) in :mod:`.gltf_lod` and :mod:`animlod.pipelines`.
"""

from .gltf_lod import read_lod_chains
from .gltf_read import GltfScene, read_gltf, read_node_motions, read_skinned
from .gltf_write import write_glb

__all__ = ["GltfScene", "read_gltf", "read_lod_chains", "read_node_motions", "read_skinned", "write_glb"]
