"""The bad-input promise through the command line: each case of issue 12 (and its neighbours)
ends with exit code 2 and one line ``animlod CMD: error: WHERE: WHAT`` naming the file and the
element, with nothing on stderr before it. Cases are grouped by class (readers, options,
outputs, core arrays) for README's count."""

from __future__ import annotations

import re
import struct
import time
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pygltflib
import pytest

from animlod import synth
from animlod.cli import main
from animlod.io import FormatError, read_gltf, write_glb, write_npz
from animlod.io.bvh import write_bvh
from animlod.metrics import surface_error
from animlod.model import AnimatedMesh

ERROR_LINE = re.compile(r"^animlod (\w+): error: (\S[^:]*): (.+)$")


def _small_glb(path: Path) -> Path:
    skin, motion = synth.bending_cylinder_skinned(frames=3, rings=4, segments=6)
    write_glb(path, skin, [motion])
    return path


def _edit_gltf(path: Path, edit: Callable[[pygltflib.GLTF2, bytearray], None], out: Path) -> Path:
    """Load ``path`` with pygltflib, let ``edit`` change the document and its binary blob, save ``out``."""
    gltf = pygltflib.GLTF2().load(str(path))
    blob = bytearray(gltf.binary_blob())
    edit(gltf, blob)
    gltf.set_binary_blob(bytes(blob))
    if out.suffix == ".gltf":
        gltf.convert_buffers(pygltflib.BufferFormat.DATAURI)
    gltf.save(str(out))
    return out


def _accessor_floats(gltf: pygltflib.GLTF2, blob: bytearray, index: int) -> np.ndarray:
    accessor = gltf.accessors[index]
    view = gltf.bufferViews[accessor.bufferView]
    start = (view.byteOffset or 0) + (accessor.byteOffset or 0)
    return np.frombuffer(memoryview(blob)[start : view.byteOffset + view.byteLength], "<f4")


def _last_key_at(seconds: float) -> Callable:
    def edit(gltf, blob):
        times = _accessor_floats(gltf, blob, gltf.animations[0].samplers[0].input)
        times[gltf.accessors[gltf.animations[0].samplers[0].input].count - 1] = seconds

    return edit


def _singular_inverse_bind(gltf, blob) -> None:
    _accessor_floats(gltf, blob, gltf.skins[0].inverseBindMatrices)[16:32] = 0.0  # joint 1


def _row_major_inverse_bind(gltf, blob) -> None:
    """Every inverse bind matrix stored transposed, as hand-written exporters do: the translation
    lands in the last row, which skinning takes for w."""
    matrices = _accessor_floats(gltf, blob, gltf.skins[0].inverseBindMatrices).reshape(-1, 4, 4)
    matrices[:] = matrices.transpose(0, 2, 1).copy()


def _json_edit(change: Callable[[dict], None]) -> Callable:
    def edit(gltf, blob):
        document = gltf.to_dict()
        change(document)
        for key in ("nodes", "scene", "animations"):
            if key in document:
                setattr(gltf, key, document[key])

    return edit


def _npz(path: Path, **arrays) -> Path:
    keys = {"format_version": np.int32(1), "faces": np.array([[0, 1, 2]], np.int32),
            "frames": np.eye(3, dtype=np.float32)[None], "fps": np.float64(30.0)}  # fmt: skip
    keys.update(arrays)
    np.savez(path, **keys)
    return path


def _npz_with_giant_shape(path: Path) -> Path:
    """A valid archive whose frames.npy header then declares (100000, 100000, 3) float32 (112 GiB)."""
    _npz(path)
    with zipfile.ZipFile(path) as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    members["frames.npy"] = members["frames.npy"].replace(b"(1, 3, 3)", b"(100000, 100000, 3)")
    with zipfile.ZipFile(path, "w") as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    return path


def _npz_with_text_member(path: Path) -> Path:
    _npz(path)
    with zipfile.ZipFile(path) as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    members["fps.npy"] = b"not an array at all"
    with zipfile.ZipFile(path, "w") as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    return path


def _bvh(path: Path, offset: str) -> Path:
    path.write_text(
        "HIERARCHY\nROOT hips\n{\n  OFFSET 0 0 0\n"
        "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
        f"  JOINT leg\n  {{\n    OFFSET {offset}\n    CHANNELS 3 Zrotation Xrotation Yrotation\n"
        "    End Site\n    {\n      OFFSET 0 -1 0\n    }\n  }\n}\nMOTION\nFrames: 2\nFrame Time: 0.0333333\n"
        "0 0 0 0 0 0 0 0 0\n0 0 0 0 0 0 10 0 0\n"
    )
    return path


# (class, name, make(tmp_path) -> argv, expected substring of the error line)
CASES: list[tuple[str, str, Callable[[Path], list[str]], str]] = [
    ("readers", "empty glb", lambda t: ["simplify", str(_write(t / "empty.glb", b"")), "-o", str(t / "o")],
     "empty.glb: file: empty file"),
    ("readers", "a BVH named .gltf", lambda t: ["info", str(_bvh(t / "walk.gltf", "0 -1 0"))],
     "walk.gltf: file: not a glTF file: neither GLB (magic 'glTF') nor a JSON object"),
    ("readers", "a BVH whose every CHANNELS is 0", lambda t: ["info", str(_write(t / "pose.bvh", _bvh(
        t / "x.bvh", "0 -1 0").read_bytes().replace(b"CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation "
        b"Yrotation", b"CHANNELS 0").replace(b"CHANNELS 3 Zrotation Xrotation Yrotation", b"CHANNELS 0")
        .replace(b"0 0 0 0 0 0 0 0 0\n0 0 0 0 0 0 10 0 0\n", b"\n\n")))],
     "pose.bvh: HIERARCHY: no joint has channels (every CHANNELS is 0): the file holds no motion"),
    ("readers", "a BVH without its Frame Time line", lambda t: ["info", str(_write(t / "rows.bvh", _bvh(
        t / "x.bvh", "0 -1 0").read_bytes().replace(b"Frame Time: 0.0333333\n", b"").replace(
        b"0 0 0 0 0 0 0 0 0\n", b" ".join([b"1.5"] * 200) + b"\n")))],  # a row quoted whole was 799 characters
     "rows.bvh: line 18: expected 'Frame Time: SECONDS' > 0 with a finite frame rate, found '" + "1.5 " * 15
     + "'... (799 characters)"),
    ("readers", "gltf nesting 100,000 deep", lambda t: ["info", str(_write(t / "deep.gltf",
        b'{"asset": {"version": "2.0"}, "extras": ' + b"[" * 100_000 + b"]" * 100_000 + b"}"))],
     "deep.gltf: JSON: nests deeper than 100 levels"),
    ("readers", "glb nesting 100,000 deep", lambda t: ["info", str(_write(t / "deep.glb", _glb_bytes(
        b'{"asset": {"version": "2.0"}, "extras": ' + b"[" * 100_000 + b"]" * 100_000 + b"}")))],
     "deep.glb: GLB JSON chunk: nests deeper than 100 levels"),
    ("readers", "npz giant shape", lambda t: ["info", str(_npz_with_giant_shape(t / "giant.npz"))],
     "giant.npz: key 'frames': header declares shape (100000, 100000, 3)"),
    ("readers", "npz member not an array", lambda t: ["info", str(_npz_with_text_member(t / "text.npz"))],
     "text.npz: key 'fps': not a .npy array"),
    ("readers", "npz face index 2**40", lambda t: ["info", str(_npz(t / "f40.npz", faces=np.array([[0, 1, 2**40]])))],
     "f40.npz: mesh: faces: face 0 [0, 1, 1099511627776] has an index outside [0, 3)"),
    ("readers", "npz face index 2**32 + 2", lambda t: ["info", str(_npz(t / "f32.npz",
        faces=np.array([[0, 1, 2**32 + 2]])))], "has an index outside [0, 3)"),
    ("readers", "glb keys to 30,000 s", lambda t: ["info", str(_edit_gltf(_small_glb(t / "a.glb"),
        _last_key_at(30_000.0), t / "long.glb"))], "long.glb: animation 'bend': lasts 30000 s: 900001 frames"),
    ("readers", "random bytes named .obj", lambda t: ["info", str(_write(t / "noise.obj",
        np.random.default_rng(0).bytes(4096)))], "noise.obj: byte"),
    ("readers", "another format's text named .obj", lambda t: ["info", str(_write(t / "map.obj",
        b"# gravitywars' levels\n****--0\n**..*--1\n"))],  # fmt: skip
     "map.obj: line 2: '****--0' is not an OBJ statement: not a Wavefront OBJ file?"),
    ("readers", "empty obj frame", lambda t: ["info", str(_write(t / "empty.obj", b"# nothing\n"))],
     "empty.obj: mesh: no vertices and no faces"),
    ("readers", "obj of polylines only", lambda t: ["info", str(_write(t / "axes.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nl 1 3\n"))],  # fmt: skip
     "axes.obj: line 4: 2 polylines ('l') and no face: animlod simplifies surfaces"),
    ("readers", "obj without faces", lambda t: ["info", str(_write(t / "points.obj", b"v 0 0 0\nv 1 0 0\n"))],
     "points.obj: mesh: 2 vertices but no faces"),
    ("readers", "glTF channel on node 9999", lambda t: ["info", str(_edit_gltf(_small_glb(t / "a.glb"),
        _json_edit(lambda d: d["animations"][0]["channels"][0]["target"].update(node=9999)), t / "n.gltf"))],
     "n.gltf: animation 0 channel 0 target: refers to node 9999"),
    ("readers", "glTF nodes is an object", lambda t: ["info", str(_gltf(t / "o.gltf",
        b'{"nodes": {}}'))], "o.gltf: nodes: must be an array, got dict"),
    ("readers", "glTF 1.0 document", lambda t: ["info", str(_write(t / "v1.gltf",
        b'{"asset": {"version": "1.0"}, "accessors": {"a": {}}}'))],
     "v1.gltf: asset: glTF version '1.0' is not 2.x; convert it to glTF 2.0 first"),
    ("readers", "glTF 0.8 document", lambda t: ["info", str(_write(t / "v08.gltf",  # Qt 3D's wine.gltf
        b'{"asset": {"version": 0.8}, "accessors": {"a": {}}}'))],
     "v08.gltf: asset: glTF version 0.8 is not 2.x; convert it to glTF 2.0 first"),
    ("readers", "glTF 1.0 document, version an integer", lambda t: ["info", str(_write(t / "v1i.gltf",  # collada2gltf's
        b'{"asset": {"version": 1}, "accessors": {"a": {}}}'))],  # CesiumMilkTruck
     "v1i.gltf: asset: glTF version 1 is not 2.x; convert it to glTF 2.0 first"),
    ("readers", "glTF 1.0 binary file", lambda t: ["info", str(_write(t / "v1.glb",
        b"glTF" + struct.pack("<IIII", 1, 28, 8, 0) + b'{"a": 1}'))],
     "v1.glb: GLB header: container version 1 is not 2: a glTF 1.0 binary file; convert it to glTF 2.0"),
    ("readers", "glTF scene past the list", lambda t: ["info", str(_gltf(t / "s.gltf",
        b'{"scene": 3, "scenes": [{"nodes": []}]}'))],
     "s.gltf: scene: refers to scene 3, but the file has 1 scenes"),
    ("readers", "glTF texture -1 (assimp's badUint.gltf)", lambda t: ["info", str(_gltf(t / "t.gltf",
        b'{"textures": [{}], "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": -1}}}]}'))],
     "t.gltf: material 0 pbrMetallicRoughness.baseColorTexture: refers to texture -1, but the file has 1 textures"),
    ("readers", "glTF extension's texture past the list", lambda t: ["info", str(_gltf(t / "c.gltf",
        b'{"materials": [{"extensions": {"KHR_materials_clearcoat": {"clearcoatTexture": {"index": 3}}}}]}'))],
     "c.gltf: material 0 extensions.KHR_materials_clearcoat.clearcoatTexture: refers to texture 3, but the file "
     "has 0 textures"),
    ("readers", "glTF texture's image past the list", lambda t: ["info", str(_gltf(t / "i.gltf",
        b'{"textures": [{"extensions": {"EXT_texture_webp": {"source": 2}}}]}'))],
     "i.gltf: texture 0 extensions.EXT_texture_webp.source: refers to image 2, but the file has 0 images"),
    ("readers", "glTF primitive's material past the list", lambda t: ["info", str(_gltf(t / "m.gltf",
        b'{"meshes": [{"primitives": [{"attributes": {}, "material": 5}]}]}'))],
     "m.gltf: mesh 0 primitive 0 material: refers to material 5, but the file has 0 materials"),
    ("readers", "glTF unused accessor's bufferView past the list", lambda t: ["info", str(_gltf(t / "a.gltf",
        b'{"accessors": [{"bufferView": 99, "componentType": 5126, "count": 1, "type": "SCALAR"}]}'))],
     "a.gltf: accessor 0 bufferView: refers to bufferView 99, but the file has 0 bufferViews"),
    ("readers", "glTF instancing accessor past the list", lambda t: ["info", str(_gltf(t / "g.gltf",
        b'{"nodes": [{"extensions": {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": 9}}}}]}'))],
     "g.gltf: node 0 EXT_mesh_gpu_instancing TRANSLATION: refers to accessor 9, but the file has 0 accessors"),
    ("readers", "glTF light past the list", lambda t: ["info", str(_gltf(t / "l.gltf",
        b'{"extensions": {"KHR_lights_punctual": {"lights": [{"type": "point"}]}},'
        b' "nodes": [{"extensions": {"KHR_lights_punctual": {"light": 5}}}]}'))],
     "l.gltf: node 0 light: refers to light 5, but the file has 1 lights"),
    ("readers", "glTF pointer at a material past the list", lambda t: ["info", str(_edit_gltf(_small_glb(t / "a.glb"),
        _json_edit(lambda d: d["animations"][0]["channels"][0].update(target={"path": "pointer", "extensions":
            {"KHR_animation_pointer": {"pointer": "/materials/7/pbrMetallicRoughness/baseColorFactor"}}})),
        t / "p.gltf"))],
     "p.gltf: animation 0 channel 0 target pointer: refers to material 7, but the file has 0 materials"),
    ("readers", "glTF skin's skeleton past the list", lambda t: ["info", str(_gltf(t / "k.gltf",
        b'{"nodes": [{}], "skins": [{"joints": [0], "skeleton": 4}]}'))],
     "k.gltf: skin 0 skeleton: refers to node 4, but the file has 1 nodes"),
    ("readers", "glTF extension that is no object", lambda t: ["info", str(_gltf(t / "e.gltf",
        b'{"textures": [{"extensions": {"KHR_texture_basisu": 7}}]}'))],
     "e.gltf: textures[0].extensions.KHR_texture_basisu: expected an object, got 7"),
    ("readers", "BVH OFFSET 1e300", lambda t: ["info", str(_bvh(t / "far.bvh", "0 1e300 0"))],
     "far.bvh: line 8: OFFSET of joint 'leg': value 1e300 is beyond"),
    ("readers", "singular inverse bind matrix", lambda t: ["info", str(_edit_gltf(_small_glb(t / "a.glb"),
        _singular_inverse_bind, t / "ibm.glb"))],
     "ibm.glb: skin 0 inverseBindMatrices: inverse bind matrix of joint 1"),
    ("readers", "row-major inverse bind matrices", lambda t: ["info", str(_edit_gltf(_small_glb(t / "a.glb"),
        _row_major_inverse_bind, t / "rm.glb"))],
     "rm.glb: skin 0 inverseBindMatrices: inverse bind matrix of joint 1 (node 1 'Bend') has a last row of (0, -1, 0, "
     "1), not (0, 0, 0, 1); written row-major instead of column-major?"),
    ("readers", "row-major node matrix", lambda t: ["info", str(_edit_gltf(_small_glb(t / "a.glb"),
        _json_edit(lambda d: d["nodes"][0].update(matrix=[1, 0, 0, 2, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1])),
        t / "m.gltf"))],
     "m.gltf: node 0 'Root': matrix has a last row of (2, 0, 0, 1), not (0, 0, 0, 1); written row-major"),
    ("readers", "truncated GLB", lambda t: ["info", str(_write(t / "cut.glb",
        _small_glb(t / "a.glb").read_bytes()[:500]))],
     "cut.glb: GLB header: file is truncated"),
    ("options", "unknown float", lambda t: ["simplify", str(_npz(t / "m.npz")), "-o", str(t / "o"), "--ratio", "x"],
     "--ratio: invalid float value: 'x'"),
    ("options", "ratio out of range", lambda t: ["simplify", str(_npz(t / "m.npz")), "-o", str(t / "o"),
        "--ratio", "2"], "--ratio: every ratio must be in (0, 1]"),
    ("options", "missing input", lambda t: ["info", str(t / "nothing.bvh")], "nothing.bvh: file: does not exist"),
    ("outputs", "output folder is a file", lambda t: ["simplify", str(_npz(t / "m.npz")), "-o",
        str(_write(t / "taken", b"x"))], "taken: is a file where the output needs a folder"),
    ("outputs", "output folder under a file", lambda t: ["motion", str(_bvh(t / "m.bvh", "0 -1 0")), "-o",
        str(_write(t / "file", b"x") / "sub"), "--levels", "2"], "file: is a file where the output needs a folder"),
    ("core arrays", "every vertex at one point", lambda t: ["simplify", str(_npz(t / "point.npz",
        faces=np.array([[0, 1, 2], [0, 2, 3]]), frames=np.zeros((2, 4, 3), np.float32))), "-o", str(t / "o")],
     "point.npz: faces: every face is degenerate"),
]  # fmt: skip


def _write(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path


def _gltf(path: Path, properties: bytes) -> Path:
    """A glTF 2.0 document at ``path``: ``properties`` (a JSON object's text) beside its asset."""
    return _write(path, b'{"asset": {"version": "2.0"}, ' + properties[1:])


def _glb_bytes(json_chunk: bytes) -> bytes:
    json_chunk += b" " * (-len(json_chunk) % 4)
    header = b"glTF" + struct.pack("<II", 2, 20 + len(json_chunk))
    return header + struct.pack("<I", len(json_chunk)) + b"JSON" + json_chunk


@pytest.mark.parametrize("kind, name, make, expected", CASES, ids=[f"{c[0]}: {c[1]}" for c in CASES])
def test_bad_input_is_one_error_line(tmp_path, capfd, kind, name, make, expected) -> None:
    argv = make(tmp_path)
    capfd.readouterr()
    start = time.perf_counter()
    assert main(argv) == 2
    seconds = time.perf_counter() - start
    err = capfd.readouterr().err
    lines = err.splitlines()
    assert len(lines) == 1, err
    match = ERROR_LINE.match(lines[0])
    assert match and match.group(1) == argv[0], lines[0]
    assert expected in lines[0]
    assert seconds < 30, f"{name}: {seconds:.1f} s"


def test_a_failed_run_prints_no_warning_or_progress_before_its_error(tmp_path, capfd, monkeypatch) -> None:
    """A command that draws a progress bar and triggers a numpy RuntimeWarning, then fails."""
    import animlod.cli.info as info

    def noisy_then_failing(args) -> int:
        from tqdm import tqdm

        bar = tqdm(total=10, desc="AQEM")
        bar.update(4)
        np.float64(0.0) / np.float64(0.0)  # RuntimeWarning: invalid value encountered
        raise ValueError("faces: face 3 is degenerate")

    monkeypatch.setattr(info, "run", noisy_then_failing)
    assert main(["info", str(tmp_path / "mesh.npz")]) == 2
    assert capfd.readouterr().err == f"animlod info: error: {tmp_path / 'mesh.npz'}: faces: face 3 is degenerate\n"


def test_a_successful_run_keeps_its_warnings_as_lines_after_it(tmp_path, capfd, monkeypatch) -> None:
    import animlod.cli.info as info

    def warning_then_success(args) -> int:
        np.float64(0.0) / np.float64(0.0)
        print("done")
        return 0

    monkeypatch.setattr(info, "run", warning_then_success)
    assert main(["info", "x"]) == 0
    captured = capfd.readouterr()
    assert captured.out == "done\n"
    assert captured.err.startswith("animlod info: warning: invalid value encountered")


def test_glb_with_keys_to_30000_s_is_refused_without_sampling(tmp_path) -> None:
    path = _edit_gltf(_small_glb(tmp_path / "a.glb"), _last_key_at(30_000.0), tmp_path / "long.glb")
    start = time.perf_counter()
    with pytest.raises(FormatError, match="lasts 30000 s: 900001 frames at 30 fps, more than the limit of 100000"):
        read_gltf(path)
    assert time.perf_counter() - start < 2.0  # refused before 900,001 frames are sampled


def test_animation_frame_limit_is_configurable(tmp_path, monkeypatch) -> None:
    path = _edit_gltf(_small_glb(tmp_path / "a.glb"), _last_key_at(40.0), tmp_path / "forty.glb")
    assert read_gltf(path).motions[0].frame_count == 1201
    monkeypatch.setenv("ANIMLOD_MAX_ANIMATION_FRAMES", "1000")
    with pytest.raises(FormatError, match="animation 'bend': lasts 40 s: 1201 frames at 30 fps, more than the limit"):
        read_gltf(path)


def test_hausdorff_of_a_mesh_collapsed_to_one_point_is_not_nan(tmp_path) -> None:
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    point = AnimatedMesh(faces, np.ones((2, 4, 3), np.float32))
    with np.errstate(all="raise"):
        summary = surface_error(point, point, samples=50).summary()
    assert summary == {"hausdorff_mean": 0.0, "hausdorff_max": 0.0, "rms_mean": 0.0, "rms_max": 0.0}
    spread = AnimatedMesh(faces, np.random.default_rng(1).random((2, 4, 3)))
    assert np.isinf(surface_error(point, spread, samples=50).summary()["hausdorff_max"])


@pytest.mark.parametrize(
    "faces, message",
    [
        (np.array([[0, 1, 2**40]]), "face 0 [0, 1, 1099511627776] has an index outside [0, 3)"),
        (np.array([[0, 1, 2**32 + 2]]), "face 0 [0, 1, 4294967298] has an index outside [0, 3)"),
        (np.array([[0, 1, 1.9]]), "face 0 [0.0, 1.0, 1.9] has an index that is not a whole number"),
        (np.array([[0, 1, -(2**32) + 1]]), "has an index outside [0, 3)"),
    ],
)
def test_face_indices_are_checked_before_the_int32_cast(faces, message) -> None:
    with pytest.raises(ValueError, match=re.escape(message)):
        AnimatedMesh(faces, np.eye(3, dtype=np.float32)[None])


def test_whole_float_and_unsigned_face_indices_still_read() -> None:
    frames = np.eye(3, dtype=np.float32)[None]
    for faces in (np.array([[0.0, 1.0, 2.0]]), np.array([[0, 1, 2]], np.uint64)):
        np.testing.assert_array_equal(AnimatedMesh(faces, frames).faces, [[0, 1, 2]])


def test_bvh_offsets_within_the_limit_still_read(tmp_path) -> None:
    assert main(["info", str(_bvh(tmp_path / "ok.bvh", "0 -1e11 0"))]) == 0
    write_bvh(tmp_path / "back.bvh", synth.humanoid_motion(synth.humanoid_skeleton(), "walk"))
    assert main(["info", str(tmp_path / "back.bvh")]) == 0


def test_npz_round_trip_passes_the_member_checks(tmp_path) -> None:
    mesh = synth.twisting_bar(frames=3)
    write_npz(tmp_path / "bar.npz", mesh)
    assert main(["info", str(tmp_path / "bar.npz")]) == 0


def test_accessor_of_zeros_is_bounded_by_the_file(tmp_path) -> None:
    """An accessor without a bufferView is zeros; 2**32 - 1 MAT4 of them (275 GB) is refused."""
    path = _write(tmp_path / "zeros.gltf", (
        b'{"asset": {"version": "2.0"}, "accessors": [{"componentType": 5126, "count": 4294967295, "type": "MAT4"}],'
        b' "nodes": [{"name": "a"}, {"name": "b"}], "skins": [{"joints": [0, 1], "inverseBindMatrices": 0}],'
        b' "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}]}'
    ))  # fmt: skip
    from animlod.io.gltf_document import GltfDocument

    doc = GltfDocument(path)
    with pytest.raises(FormatError, match=r"accessor 0 \(probe\): count 4294967295 without a bufferView needs"):
        doc.accessor(0, "probe")
