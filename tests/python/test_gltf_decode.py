"""The glTF object model from animlod's decoder against pygltflib's own (dataclasses_json), and
the JSON type errors the decoder reports instead of bending the value."""

from __future__ import annotations

import dataclasses
import json
import warnings
from pathlib import Path
from typing import Any

import pygltflib
import pytest

from animlod.io import FormatError, read_gltf
from animlod.io.gltf_decode import decode_gltf
from animlod.io.gltf_document import GltfDocument
from animlod.io.gltf_write import write_glb
from animlod.synth import humanoid, humanoid_motion

# Every class pygltflib decodes, each with values of every JSON type it takes, and custom
# attributes, extras of several JSON types and extensions.
EVERY_CLASS = {
    "asset": {"version": "2.0", "generator": "test", "copyright": "none", "extras": {"a": [1, {"b": None}]}},
    "extensionsUsed": ["KHR_materials_unlit", "EXT_custom"],
    "extensionsRequired": ["KHR_materials_unlit"],
    "scene": 0,
    "scenes": [{"nodes": [0], "name": "scene", "extras": {"count": 3}}],
    "nodes": [
        {"children": [1], "translation": [1, 2.5, 3], "rotation": [0, 0, 0, 1], "scale": [1, 1, 1], "mesh": 0},
        {"matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1], "camera": 0, "skin": 0, "weights": [0.5]},
    ],
    "cameras": [
        {"type": "perspective", "perspective": {"yfov": 1, "znear": 0.1, "zfar": 100, "aspectRatio": 1.5}},
        {"type": "orthographic", "orthographic": {"xmag": 1, "ymag": 1, "znear": 0, "zfar": 10}},
    ],
    "meshes": [
        {
            "name": "mesh",
            "weights": [0.25],
            "primitives": [
                {
                    "attributes": {"POSITION": 0, "NORMAL": 1, "_CUSTOM": 2, "TEXCOORD_3": 2},
                    "indices": 3,
                    "mode": 4,
                    "material": 0,
                    "targets": [{"POSITION": 0, "NORMAL": 1}],
                    "extensions": {"EXT_custom": {"x": True}},
                }
            ],
        }
    ],
    "materials": [
        {
            "name": "material",
            "pbrMetallicRoughness": {
                "baseColorFactor": [1, 1, 1, 1],
                "baseColorTexture": {"index": 0, "texCoord": 1},
                "metallicFactor": 0,
                "roughnessFactor": 0.5,
                "metallicRoughnessTexture": {"index": 0},
            },
            "normalTexture": {"index": 0, "scale": 2},
            "occlusionTexture": {"index": 0, "strength": 0.5},
            "emissiveTexture": {"index": 0},
            "emissiveFactor": [0, 0, 0],
            "alphaMode": "MASK",
            "alphaCutoff": 0.25,
            "doubleSided": True,
            "extensions": {"KHR_materials_unlit": {}},
        }
    ],
    "textures": [{"sampler": 0, "source": 0}],
    "samplers": [{"magFilter": 9729, "minFilter": 9987, "wrapS": 33071, "wrapT": 10497}],
    "images": [{"uri": "texture.png", "mimeType": "image/png"}, {"bufferView": 0, "mimeType": "image/jpeg"}],
    "skins": [{"joints": [0, 1], "inverseBindMatrices": 2, "skeleton": 0}],
    "animations": [
        {
            "name": "move",
            "channels": [{"sampler": 0, "target": {"node": 1, "path": "translation"}}],
            "samplers": [{"input": 1, "output": 0, "interpolation": "STEP"}],
        }
    ],
    "buffers": [{"byteLength": 64, "uri": "data.bin"}],
    "bufferViews": [{"buffer": 0, "byteOffset": 4, "byteLength": 60, "byteStride": 12, "target": 34962}],
    "accessors": [
        {"bufferView": 0, "byteOffset": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0]},
        {
            "componentType": 5123,
            "normalized": True,
            "count": 3,
            "type": "VEC3",
            "sparse": {
                "count": 1,
                "indices": {"bufferView": 0, "byteOffset": 0, "componentType": 5123},
                "values": {"bufferView": 0, "byteOffset": 8},
            },
        },
        {"bufferView": 0, "componentType": 5126, "count": 2, "type": "MAT4", "name": "inverse binds"},
        {"bufferView": 0, "componentType": 5125, "count": 3, "type": "SCALAR", "max": [2.0]},
    ],
    "extensions": {"EXT_custom": {"list": [1, 2]}},
    "extras": {"author": "test"},
}


def _plain(value: Any) -> Any:
    """An object model as plain data; a primitive's attributes as the names that are set, whether
    pygltflib left them as a dict (morph targets) or an Attributes object."""
    if isinstance(value, pygltflib.Attributes):
        value = vars(value)
    if dataclasses.is_dataclass(value):
        return {field.name: _plain(getattr(value, field.name)) for field in dataclasses.fields(value)}
    if isinstance(value, dict):
        return {key: _plain(item) for key, item in value.items() if item is not None}
    if isinstance(value, list):
        return [_plain(item) for item in value]
    return value


def _pygltflib_decode(document: dict) -> pygltflib.GLTF2:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return pygltflib.GLTF2.gltf_from_json(json.dumps(document))


def _assert_same_as_pygltflib(path: str, document: dict) -> None:
    ours = decode_gltf(path, json.loads(json.dumps(document)))
    assert _plain(ours) == _plain(_pygltflib_decode(document))


def test_every_class_decodes_as_pygltflib_decodes_it():
    _assert_same_as_pygltflib("every_class.gltf", EVERY_CLASS)


def test_the_result_shares_nothing_with_the_input():
    document = json.loads(json.dumps(EVERY_CLASS))
    gltf = decode_gltf("every_class.gltf", document)
    document["asset"]["extras"]["a"][1]["b"] = "changed"
    document["extensions"]["EXT_custom"]["list"].append(3)
    assert gltf.asset.extras == {"a": [1, {"b": None}]}
    assert gltf.extensions == {"EXT_custom": {"list": [1, 2]}}


def test_a_written_character_decodes_as_pygltflib_decodes_it(tmp_path):
    mesh = humanoid()
    path = tmp_path / "humanoid.glb"
    write_glb(path, mesh, [humanoid_motion(mesh.skeleton, "walk")])
    document = GltfDocument(path)
    assert _plain(document.gltf) == _plain(pygltflib.GLTF2.load_from_bytes(path.read_bytes()))
    assert document.gltf.binary_blob() == pygltflib.GLTF2.load_from_bytes(path.read_bytes()).binary_blob()


def _dev_gltf_files(data_dir: Path) -> list[Path]:
    return sorted(p for folder in ("gltf", "morph") for p in (data_dir / folder).glob("*.gl*"))


def test_every_dev_gltf_decodes_as_pygltflib_decodes_it(data_dir):
    files = _dev_gltf_files(data_dir)
    assert files
    for path in files:
        document = GltfDocument(path)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            reference = pygltflib.GLTF2.load(str(path))
        assert _plain(document.gltf) == _plain(reference), path.name
        assert document.gltf.binary_blob() == reference.binary_blob(), path.name


def _edited(edit) -> dict:
    document = json.loads(json.dumps(EVERY_CLASS))
    edit(document)
    return document


@pytest.mark.parametrize(
    ("edit", "where", "reason"),
    [
        (lambda d: d["accessors"][0].update(count=2.5), "accessors[0].count", "expected an integer, got 2.5"),
        (lambda d: d["accessors"][0].update(count=True), "accessors[0].count", "expected an integer, got True"),
        (lambda d: d["accessors"][0].update(componentType="5126"), "accessors[0].componentType",
         "expected an integer, got '5126'"),
        (lambda d: d["nodes"][0].update(translation="123"), "nodes[0].translation", "expected an array, got '123'"),
        (lambda d: d["nodes"][0].update(translation=[None, 0, 0]), "nodes[0].translation[0]",
         "null (glTF arrays hold no nulls)"),
        (lambda d: d["nodes"][0].update(children=[1.7]), "nodes[0].children[0]", "expected an integer, got 1.7"),
        (lambda d: d["nodes"].append(5), "nodes[2]", "expected an object, got 5"),
        (lambda d: d["asset"].update(version=2.0), "asset.version", "expected a string, got 2.0"),
        (lambda d: d["accessors"][1].update(normalized=1), "accessors[1].normalized", "expected true or false, got 1"),
        (lambda d: d["buffers"][0].update(uri=5), "buffers[0].uri", "expected a string, got 5"),
        (lambda d: d["meshes"][0]["primitives"][0].update(attributes=[0]), "meshes[0].primitives[0].attributes",
         "expected an object, got [0]"),
        (lambda d: d["meshes"][0]["primitives"][0]["attributes"].update(NORMAL="1"),
         "meshes[0].primitives[0].attributes.NORMAL", "expected an integer, got '1'"),
        (lambda d: d["meshes"][0]["primitives"][0].update(extensions=[1]), "meshes[0].primitives[0].extensions",
         "expected an object, got [1]"),
        (lambda d: d["cameras"][0].update(perspective="wide"), "cameras[0].perspective",
         "expected an object, got 'wide'"),
    ],
)  # fmt: skip
def test_a_value_of_the_wrong_json_type_is_named(edit, where, reason):
    with pytest.raises(FormatError) as caught:
        decode_gltf("bad.gltf", _edited(edit))
    assert str(caught.value) == f"bad.gltf: {where}: {reason}"


@pytest.mark.parametrize(
    ("edit", "check"),
    [
        # JSON Schema's integers include 3.0.
        (lambda d: d["accessors"][0].update(count=3.0), lambda g: g.accessors[0].count == 3),
        # glTF 2.0 allows extras of any JSON type (pygltflib refuses all but objects).
        (lambda d: d["nodes"][0].update(extras="note"), lambda g: g.nodes[0].extras == "note"),
        # A number where a name belongs is its text (pygltflib's reading), not a refused file.
        (lambda d: d["nodes"][0].update(name=7), lambda g: g.nodes[0].name == "7"),
        # A null property is taken as absent: the field's default.
        (lambda d: d["accessors"][0].update(byteOffset=None), lambda g: g.accessors[0].byteOffset == 0),
        # Empty attributes are Attributes with nothing set (pygltflib leaves a dict).
        (lambda d: d["meshes"][0]["primitives"][0].update(attributes={}),
         lambda g: not any(vars(g.meshes[0].primitives[0].attributes).values())),
    ],
)  # fmt: skip
def test_values_glTF_allows_are_kept(edit, check):
    assert check(decode_gltf("ok.gltf", _edited(edit)))


def test_a_primitive_without_attributes_is_refused_by_the_reader(tmp_path):
    path = tmp_path / "empty_attributes.gltf"
    document = {
        "asset": {"version": "2.0"},
        "meshes": [{"primitives": [{"attributes": {}}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
    }
    path.write_text(json.dumps(document))
    with pytest.raises(FormatError, match="has no POSITION attribute"):
        read_gltf(path)


def test_a_number_given_as_a_label_is_written_as_its_text(tmp_path):
    # assimp's badString.gltf names its scene 42: read as "42", it was copied into outputs as 42,
    # which glTF's schema refuses.
    path = tmp_path / "numbered.gltf"
    path.write_text(json.dumps({"asset": {"version": "2.0", "generator": 3}, "scenes": [{"name": 42}]}))
    document = GltfDocument(path)
    assert document.json["scenes"][0]["name"] == "42" and document.json["asset"]["generator"] == "3"
    assert document.gltf.scenes[0].name == "42"
