"""The asset jobs: one input path and options in, files in an output folder and an
:class:`~animlod.pipelines.result.AssetResult` out.

They wrap the pipelines (:func:`simplify_document`, :func:`simplify_sequence`,
:func:`build_character`, :func:`animlod.face_lod.pipeline.run_face_lod`) with one calling
convention, ``job(source, output_folder, *, progress=None, **options)``, and one result record,
so that the batch runner treats every technique alike. The motion job is
:func:`animlod.pipelines.motion.motion_asset`.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

from ..io.detect import glb_name, input_kind
from ..io.errors import FormatError
from .result import AssetResult, LevelRow, Progress


def simplify_asset(
    source: str | os.PathLike,
    output: str | os.PathLike,
    *,
    progress: Progress | None = None,
    **options: object,
) -> AssetResult:
    """AQEM levels of a glTF document or a deforming mesh sequence, written into the folder ``output``.

    A .glb/.gltf/.vrm becomes ``<stem>_lod.glb`` (.vrm for a .vrm; one LoD GLB, see
    :func:`simplify_document`; with ``separate=True`` one ``<stem>_lod<i>.glb`` per level); an
    NPZ or OBJ/PLY sequence becomes one ``<stem>_lod<i>`` per level in its own format (see
    :func:`simplify_sequence`).

    Parameters
    ----------
    source : the input file, folder or glob.
    output : the folder to write into (created when missing).
    progress : called with (fraction done or None, a line of text).
    **options : keyword arguments of :func:`simplify_document` (glTF) or :func:`simplify_sequence`
        (sequences), ``ratios`` included, and the AQEM options of :func:`animlod.simplify_animated`.

    Raises
    ------
    FormatError for input it cannot read (a BVH holds no mesh); ValueError for bad options.
    """
    started = time.perf_counter()
    kind = input_kind(source)
    folder = Path(output)
    if kind == "gltf":
        from .lod_document import simplify_document

        separate = bool(options.get("separate", False))
        target = folder if separate else folder / glb_name(source, "_lod")
        lines = (lambda line: progress(None, line)) if progress else None
        report = simplify_document(source, target, progress=lines, **options)
        rows = [
            LevelRow(level.level, drawable.label, level.faces, None, level.error, level.relative_error)
            for drawable in report.drawables
            for level in drawable.levels
        ]
        notes = [f"{drawable.label}: {note}" for drawable in report.drawables for note in drawable.notes]
        return AssetResult("simplify", os.fspath(source), report.outputs, rows, time.perf_counter() - started, notes)
    if kind in ("npz", "sequence"):
        from .lod_sequence import simplify_sequence

        counts = (lambda done, total: progress(done / total if total else None, "AQEM collapses")) if progress else None
        report = simplify_sequence(source, folder, progress=counts, **options)
        rows = [LevelRow(0, "", report.original.face_count, None, 0.0, 0.0)]
        for index, level in enumerate(report.levels, start=1):
            relative = level.surface["hausdorff_max"] if level.surface else None
            rows.append(LevelRow(index, "", level.faces, None, level.error, relative))
        outputs = [level.path for level in report.levels]
        return AssetResult("simplify", os.fspath(source), outputs, rows, time.perf_counter() - started, report.notes)
    reason = f"a {kind} file holds no mesh; simplify needs one (try the motion job)"
    raise FormatError(os.fspath(source), "file", reason)


def character_asset(
    source: str | os.PathLike,
    output: str | os.PathLike,
    *,
    progress: Progress | None = None,
    **options: object,
) -> AssetResult:
    """Geometry x motion levels of a skinned, animated glTF character, written as
    ``<stem>_character.glb`` into the folder ``output`` (see :func:`build_character`).

    ``options`` are the keyword arguments of :func:`build_character` (``ratios``, ``solver``,
    ``frame_budget`` ... and the AQEM options). Raises FormatError for input that is not a
    glTF with a skinned, animated mesh.
    """
    started = time.perf_counter()
    kind = input_kind(source)
    if kind != "gltf":
        needs = "the job needs a .glb/.gltf/.vrm"
        raise FormatError(os.fspath(source), "file", f"a {kind} file is not a character; {needs}")
    from .character import build_character

    target = Path(output) / glb_name(source, "_character")
    lines = (lambda line: progress(None, line)) if progress else None
    report = build_character(source, target, progress=lines, **options)
    rows = [
        LevelRow(level.level, label, level.faces, level.joints, level.error, level.relative_error)
        for label, levels in report.chains.items()
        for level in levels
    ]
    return AssetResult("character", os.fspath(source), [target], rows, time.perf_counter() - started, report.notes)


def face_asset(
    source: str | os.PathLike,
    output: str | os.PathLike,
    *,
    progress: Progress | None = None,
    **options: object,
) -> AssetResult:
    """Facial LoD of a glTF with morph targets or a folder of OBJ/PLY poses (neutral first or
    named ``*neutral*``), written as ``<stem>_lod.glb`` and ``<stem>_face_lod.json`` into the
    folder ``output`` (see :func:`animlod.face_lod.pipeline.run_face_lod`).

    ``options`` are the keyword arguments of ``run_face_lod`` (``ratios``, ``face_counts``,
    ``target_fractions``, ``neutral``, ``repeats``, ``error_frames`` ...). Rows: triangles and
    the measured surface error per level (asset units, from the written manifest, and relative to
    the bounding-box diagonal). Raises FormatError for input that is not a face.
    """
    started = time.perf_counter()
    from ..face_lod.pipeline import run_face_lod
    from ..io.manifest import read_lod_manifest

    if progress is not None:
        progress(None, "face levels")
    run = run_face_lod(source, output, **options)  # type: ignore[arg-type]
    manifest = next(path for path in run.files if path.name.endswith("_face_lod.json"))
    errors = [level["error"] for level in read_lod_manifest(manifest)["levels"]]
    level, triangles = run.columns.index("level"), run.columns.index("triangles")
    relative = run.columns.index("Hausdorff (% of diagonal)")
    rows = [
        LevelRow(int(row[level]), "", int(row[triangles]), None, float(error), float(row[relative]) / 100.0)
        for row, error in zip(run.rows, errors)
    ]
    return AssetResult("face", os.fspath(source), list(run.files), rows, time.perf_counter() - started, run.notes)
