"""What a batch runs: the assets of a folder, a glob or a manifest, each with its job and options.

SPEC forms (:func:`read_spec`):

- a folder: every .glb/.gltf/.vrm/.bvh/.npz file in and below it is an asset, and every folder
  holding OBJ/PLY frames is one sequence asset, or each of its files one when they are separate
  meshes (:func:`animlod.io.detect.separate_meshes`); hidden files and folders, links to no file
  and batch outputs are skipped; the output of ``a/b/hero.glb`` goes to ``OUT/a/b/hero``,
  and where a name would repeat or hold another asset's folder (``hero.glb`` and ``hero.bvh``,
  ``hero.glb`` beside ``hero/walk.bvh``) it takes its input's kind: ``hero_glb``, ``hero_frames``;
- a glob (``"library/**/*.glb"``): every match is an asset (a file, or a folder of frames);
- a manifest (``.toml`` or ``.json``), paths relative to the manifest's folder::

      [defaults]                 # optional: job and options for every asset
      ratios = [0.5, 0.25]

      [[assets]]
      input = "characters/hero.glb"
      job = "character"          # optional; by default simplify for meshes, motion for BVH and glTF clips alone
      name = "hero"              # optional: its folder under OUT
      solver = "newton"          # any option of the job

      [[assets]]
      glob = "crowd/*.glb"       # every match an asset, with these options
      frame_budget = 24

The whole spec is checked before anything runs (:class:`SpecError` names the file, the element
and the reason): unknown jobs and options, option types and values, missing inputs, clashing
names.
"""

from __future__ import annotations

import dataclasses
import glob
import os
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath

from ..io.detect import BATCH_STATE, MODEL_SUFFIXES, assets_in, input_kind, is_pattern, unread_models_note
from ..io.errors import FormatError
from ..io.meshseq import MESH_SUFFIXES
from .jobs import check_options, check_values, default_job, find_job

MANIFEST_SUFFIXES = (".toml", ".json")
_ENTRY_KEYS = frozenset({"input", "glob", "name", "job"})
_MANIFEST_KEYS = frozenset({"defaults", "assets"})
# Names under OUT that belong to the runner, not to an asset.
RESERVED_NAMES = frozenset({"catalogue.parquet", BATCH_STATE})


class SpecError(FormatError):
    """A spec that cannot run: names the file (manifest, folder or glob), the element and the reason."""


@dataclass(frozen=True)
class AssetSpec:
    """One asset of a batch.

    name : its folder under the output, a relative POSIX path (``"characters/hero"``).
    input : the input as the pipelines read it (a file, a folder of frames or a frame glob).
    kind : :func:`animlod.io.detect.input_kind` of the input.
    job : a built-in job's name or ``"module:function"``.
    options : keyword arguments of the job (JSON values).
    """

    name: str
    input: str
    kind: str
    job: str
    options: dict = field(default_factory=dict)


def read_spec(spec: str | os.PathLike, job: str | None = None, options: dict | None = None) -> list[AssetSpec]:
    """The assets of ``spec`` (a folder, a glob, a manifest or a single input), checked.

    ``job`` applies to every asset of a folder or glob (a manifest entry's own job wins).
    ``options``, like a manifest's ``[defaults]``, go to every asset whose job takes them (a
    sequence's ``measure`` is not a glTF option); one that no asset takes is an error, as is an
    unknown option of a manifest entry. Raises SpecError.
    """
    text = os.fspath(spec)
    path = Path(text)
    options = dict(options or {})
    if is_pattern(text):
        matches = sorted(glob.glob(text, recursive=True))
        if not matches:
            raise SpecError(text, "pattern", "matches no file")
        base = _glob_base(text)
        found = [(match, _default_name(Path(match), base)) for match in matches]
        return _checked(text, "pattern", found, job, options)
    if not path.exists():
        raise SpecError(text, "file", "does not exist")
    if path.is_file() and path.suffix.lower() in MANIFEST_SUFFIXES:
        return _read_manifest(path, job, options)
    if path.is_dir():
        found = [(os.fspath(item), _default_name(item, path)) for item in assets_in(path)]
        if not found:
            unread = unread_models_note(path)
            reason = f"holds no asset ({', '.join(MODEL_SUFFIXES)} files or folders of frames)"
            raise SpecError(text, "folder", reason + (f", but {unread}" if unread else ""))
        if [source for source, _ in found] != [os.fspath(path)]:  # a library, not one folder of frames
            return _checked(text, "folder", found, job, options)
    return _checked(text, "input", [(text, _default_name(path, path.parent))], job, options)


def _glob_base(pattern: str) -> Path:
    fixed = Path(pattern)
    while glob.has_magic(str(fixed)):
        fixed = fixed.parent
    return fixed


def _default_name(path: Path, base: Path) -> str:
    """The input's path below ``base`` without its suffix (a folder keeps its whole name; a frame
    glob is named after the folder it starts in)."""
    if is_pattern(path):
        path = _glob_base(os.fspath(path))
    # By the path as found, links not followed: a link is named after itself, not its target.
    path, base = Path(os.path.abspath(path)), Path(os.path.abspath(base))
    relative = path.relative_to(base) if path.is_relative_to(base) else Path(path.name)
    if not path.is_dir() and relative.suffix.lower() in MODEL_SUFFIXES + MESH_SUFFIXES:
        relative = relative.with_suffix("")
    return PurePosixPath(*relative.parts).as_posix() if relative.parts else path.name


def _read_manifest(path: Path, job: str | None, options: dict) -> list[AssetSpec]:
    data = _load_manifest(path)
    if not isinstance(data, dict):
        raise SpecError(path, "document", "expected a table with 'assets' (and optional 'defaults')")
    unknown = sorted(set(data) - _MANIFEST_KEYS)
    if unknown:
        raise SpecError(path, unknown[0], "unknown key; a manifest holds 'defaults' and 'assets'")
    defaults = data.get("defaults", {})
    if not isinstance(defaults, dict):
        raise SpecError(path, "defaults", "expected a table of options")
    for key in ("input", "glob", "name"):
        if key in defaults:
            raise SpecError(path, f"defaults.{key}", "belongs to an asset, not to the defaults")
    entries = data.get("assets")
    if not isinstance(entries, list) or not entries:
        raise SpecError(path, "assets", "expected a non-empty list of assets")
    folder = path.parent
    assets: list[AssetSpec] = []
    for index, entry in enumerate(entries):
        where = f"assets[{index}]"
        if not isinstance(entry, dict):
            raise SpecError(path, where, "expected a table with 'input' or 'glob'")
        chosen_job = entry.get("job", defaults.get("job", job))
        if ("input" in entry) == ("glob" in entry):
            raise SpecError(path, where, "needs exactly one of 'input' (one asset) or 'glob' (one asset per match)")
        if "input" in entry:
            source = _manifest_path(path, f"{where}.input", entry["input"], folder)
            if not is_pattern(source) and not Path(source).exists():
                raise SpecError(path, f"{where}.input", f"{source} does not exist")
            name = entry.get("name", _default_name(Path(source), folder))
            if not isinstance(name, str):
                raise SpecError(path, f"{where}.name", f"expected a string, got {name!r}")
            sources = [(source, name)]
        else:
            pattern = _manifest_path(path, f"{where}.glob", entry["glob"], folder)
            if "name" in entry:
                raise SpecError(path, f"{where}.name", "a glob names its assets after the files it matches")
            matches = sorted(glob.glob(pattern, recursive=True))
            if not matches:
                raise SpecError(path, f"{where}.glob", f"{pattern} matches no file")
            sources = [(match, _default_name(Path(match), folder)) for match in matches]
        own = {key: value for key, value in entry.items() if key not in _ENTRY_KEYS}
        shared = {**options, **{key: value for key, value in defaults.items() if key != "job"}}
        for source, name in sources:
            assets.append(_asset(path, where, source, name, chosen_job, own, shared))
    _check_shared(path, "defaults", assets, {key: value for key, value in defaults.items() if key != "job"})
    _check_shared(path, "--set", assets, options)
    _check_names(path, assets)
    return assets


def _load_manifest(path: Path) -> object:
    try:
        data = path.read_bytes()
    except OSError as error:
        raise SpecError(path, "file", f"cannot read ({error.strerror})") from None
    if path.suffix.lower() == ".json":
        from ..io.json_limits import load_json

        return load_json(path, data)
    import tomllib

    try:
        return tomllib.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as error:
        raise SpecError(path, "document", f"not valid TOML ({error})") from None


def _manifest_path(path: Path, where: str, value: object, folder: Path) -> str:
    if not isinstance(value, str) or not value:
        raise SpecError(path, where, f"expected a path, got {value!r}")
    return value if os.path.isabs(value) else os.fspath(folder / value)


def _checked(spec: str, element: str, found: list[tuple[str, str]], job: str | None, shared: dict) -> list[AssetSpec]:
    assets = [_asset(spec, element, source, name, job, {}, shared) for source, name in found]
    _check_shared(spec, "--set", assets, shared)
    _check_names(spec, assets, unique_suffixes=True)
    return assets


def _check_shared(spec: str | Path, where: str, assets: list[AssetSpec], shared: dict) -> None:
    """SpecError for a shared option that no asset's job takes."""
    for name in shared:
        if not any(name in asset.options for asset in assets):
            jobs = ", ".join(sorted({f"{asset.job} ({asset.kind})" for asset in assets}))
            raise SpecError(spec, f"{where}.{name}", f"no asset's job takes this option (jobs here: {jobs})")


def _asset(
    spec: str | Path, where: str, source: str, name: str, job: str | None, options: dict, shared: dict
) -> AssetSpec:
    """One checked asset: ``options`` must all suit its job, ``shared`` ones are added where they
    do (a type error in one is still an error), and the values of both must be ones the job can
    run with; SpecError naming ``where`` in ``spec`` otherwise."""
    try:
        kind = input_kind(source)
    except FormatError as error:
        raise SpecError(spec, where, f"{source}: {error.reason}") from None
    job_name = job if job is not None else default_job(source, kind)
    if not isinstance(job_name, str):
        raise SpecError(spec, f"{where}.job", f"expected a job name, got {job_name!r}")
    try:
        found = find_job(job_name)
    except ValueError as error:
        raise SpecError(spec, f"{where}.job", str(error)) from None
    problem = check_options(found, kind, options)
    if problem:
        raise SpecError(spec, where, f"{source}: {problem}")
    merged = dict(options)
    for key, value in shared.items():
        if key in options:
            continue
        problem = check_options(found, kind, {key: value})
        if problem is None:
            merged[key] = value
        elif "unknown for job" not in problem and "does not take" not in problem:
            raise SpecError(spec, where, f"{source}: {problem}")
    problem = check_values(found, kind, merged)
    if problem:
        raise SpecError(spec, where, f"{source}: {problem}")
    return AssetSpec(name, source, kind, job_name, merged)


def _check_names(spec: str | Path, assets: list[AssetSpec], unique_suffixes: bool = False) -> None:
    """Names must be relative, clean and distinct, and no asset's folder may hold another's. A
    folder or glob spec, which names assets itself, first tags each name that repeats or would
    hold another asset's folder with its input's kind (see the module notes)."""
    if unique_suffixes:
        counts = Counter(asset.name for asset in assets)
        folders = {parent.as_posix() for asset in assets for parent in PurePosixPath(asset.name).parents}
        for index, asset in enumerate(assets):
            if counts[asset.name] > 1 or asset.name in folders:
                kind = "frames" if Path(asset.input).is_dir() else Path(asset.input).suffix.lstrip(".")
                assets[index] = dataclasses.replace(asset, name=f"{asset.name}_{kind}" if kind else asset.name)
    seen: dict[str, str] = {}
    for asset in assets:
        parts = PurePosixPath(asset.name).parts
        bad = (
            not asset.name
            or PurePosixPath(asset.name).is_absolute()
            or "\\" in asset.name
            or any(part in ("", ".", "..") or part.startswith(".") for part in parts)
            or parts[0] in RESERVED_NAMES
        )
        if bad:
            raise SpecError(spec, f"name {asset.name!r}", "an asset's name is a relative path without '.' parts")
        if asset.name in seen:
            raise SpecError(spec, f"name {asset.name!r}", f"given to both {seen[asset.name]} and {asset.input}")
        seen[asset.name] = asset.input
    names = set(seen)
    for name in names:  # one asset's folder may not hold another's
        parent = PurePosixPath(name).parent
        while parent != PurePosixPath("."):
            if parent.as_posix() in names:
                raise SpecError(spec, f"name {name!r}", f"lies inside the folder of asset {parent.as_posix()!r}")
            parent = parent.parent
