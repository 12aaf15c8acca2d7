"""Content hashes of an asset's inputs and options: what a rerun compares to skip an asset.

The fingerprint covers every byte the job will read (a .gltf's external buffers and images
too, every frame of a sequence), the job, its options and the animlod version, so that an
asset is redone when any of them changes and skipped otherwise, whatever the files' times.
"""

from __future__ import annotations

import glob
import hashlib
import json
import os
import warnings
from pathlib import Path

from .. import __version__
from ..io.detect import is_pattern
from ..io.errors import FormatError
from ..io.gltf_document import document_json, image_file, uri_path
from ..io.meshseq import frame_files
from .spec import AssetSpec

_CHUNK = 1 << 20
FORMAT = "animlod-batch-fingerprint/1"


def input_files(asset: AssetSpec) -> list[Path]:
    """Every file the job reads for ``asset``, in a stable order."""
    source = asset.input
    if asset.kind == "sequence":
        if is_pattern(source):
            return sorted(Path(match) for match in glob.glob(source, recursive=True) if Path(match).is_file())
        path = Path(source)
        return frame_files(path) if path.is_dir() else [path]
    path = Path(source)
    if asset.kind == "gltf":  # a .glb may name external files too (assimp's name their textures)
        return [path, *_external_files(path)]
    return [path]


def _external_files(path: Path) -> list[Path]:
    """Buffers and images a glTF names by relative URI (data: URIs are inside the file), found
    as the job finds them (an image URI with backslashes, a document in Latin-1)."""
    try:
        with warnings.catch_warnings():  # the job gives the reader's warnings
            warnings.simplefilter("ignore")
            document = document_json(path)
    except FormatError:
        return []  # the job will say what is wrong with the file
    found = []
    for key, resolve in (("buffers", uri_path), ("images", image_file)):
        items = document.get(key)
        for item in items if isinstance(items, list) else []:
            uri = item.get("uri") if isinstance(item, dict) else None
            if isinstance(uri, str) and uri and not uri.startswith("data:") and "://" not in uri:
                candidate = resolve(path, uri)
                if candidate is not None and candidate.is_file():
                    found.append(candidate)
    return sorted(set(found))


def fingerprint(asset: AssetSpec) -> tuple[str, int]:
    """(hex SHA-256 of the asset's job, options, animlod version and input bytes, total input bytes)."""
    digest = hashlib.sha256()
    header = {"format": FORMAT, "version": __version__, "job": asset.job, "kind": asset.kind, "options": asset.options}
    digest.update(json.dumps(header, sort_keys=True, separators=(",", ":"), default=str).encode())
    files = input_files(asset)
    base = Path(os.path.commonpath([os.fspath(file.resolve()) for file in files])) if files else Path()
    total = 0
    for file in files:
        name = file.resolve().relative_to(base).as_posix() if len(files) > 1 else file.name
        digest.update(f"\0{name}\0".encode())
        with open(file, "rb") as handle:
            while chunk := handle.read(_CHUNK):
                digest.update(chunk)
                total += len(chunk)
    return digest.hexdigest(), total
