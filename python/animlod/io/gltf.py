"""glTF 2.0 / GLB in and out: the public entry points.

Reading lives in :mod:`.gltf_read` (with :mod:`.gltf_document` for checked buffer access and
:mod:`.gltf_keyframes` for sampler interpolation), writing in :mod:`.gltf_write`.
"""

from .gltf_read import GltfScene, read_gltf, read_skinned
from .gltf_write import write_glb

__all__ = ["GltfScene", "read_gltf", "read_skinned", "write_glb"]
