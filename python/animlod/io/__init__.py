"""File formats: BVH, glTF 2.0 / GLB, OBJ and PLY frame sequences, NPZ."""

from .bvh import BvhLayout, read_bvh, read_bvh_with_layout, write_bvh
from .errors import FormatError
from .gltf import GltfScene, read_gltf, read_lod_chains, read_node_motions, read_skinned, write_glb
from .meshseq import (
    SequenceTexture,
    TexturedSequence,
    read_mesh,
    read_sequence,
    read_textured_sequence,
    write_mesh,
    write_sequence,
)
from .npz import read_npz, write_npz
from .obj import ObjMaterials, ObjTexture, TexturedMesh, read_obj, read_obj_textured, write_obj
from .ply import read_ply, read_ply_attributes, write_ply
from .vertex_colours import VertexColours

__all__ = [
    "BvhLayout",
    "FormatError",
    "GltfScene",
    "ObjMaterials",
    "ObjTexture",
    "SequenceTexture",
    "TexturedMesh",
    "TexturedSequence",
    "VertexColours",
    "read_bvh",
    "read_bvh_with_layout",
    "read_gltf",
    "read_lod_chains",
    "read_mesh",
    "read_node_motions",
    "read_npz",
    "read_obj",
    "read_obj_textured",
    "read_ply",
    "read_ply_attributes",
    "read_sequence",
    "read_skinned",
    "read_textured_sequence",
    "write_bvh",
    "write_glb",
    "write_mesh",
    "write_npz",
    "write_obj",
    "write_ply",
    "write_sequence",
]
