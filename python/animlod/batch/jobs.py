"""The jobs a batch can run on an asset, and the options each accepts.

A job is a function ``job(source, output_folder, *, progress=None, **options) -> AssetResult``
(see :mod:`animlod.pipelines`). The built-in ones are named (``simplify``, ``character``, ``face``,
``motion``); a studio's own job is named by its import path, ``"package.module:function"``,
and must be importable on every worker.

The options a job accepts are read from the signatures of the functions it calls and from the
core's options classes they take (:mod:`animlod.options`), and their defaults from those too,
so that a manifest is checked against the code that will run it, with no second list to keep in
step.
"""

from __future__ import annotations

import collections.abc
import functools
import importlib
import inspect
import math
import types
import typing
from collections.abc import Callable, Sequence
from dataclasses import dataclass

# The job an input gets when the spec names none, by input kind (animlod.io.detect.input_kind);
# see default_job for a glTF of clips alone.
DEFAULT_JOBS = {"gltf": "simplify", "npz": "simplify", "sequence": "simplify", "bvh": "motion"}
# Keyword arguments a manifest never sets: the runner owns progress, and a batch spreads its
# work over assets (one core each), not over the processes of one asset. Callbacks (parameters
# annotated Callable) are left out too.
# A pipeline's settings object is given by its fields (DrawableSettings, listed as a source).
# Files besides the asset (character clips) would escape its fingerprint, so reruns would miss
# their changes; a joint map only maps the joints of BVH clips, so without them it is refused.
_RESERVED = frozenset({"source", "output", "progress", "workers", "settings", "aqem", "clips", "joint_map"})


def default_job(source: str, kind: str) -> str | None:
    """The job of an asset whose spec names none: ``DEFAULT_JOBS`` by kind, but ``motion`` for a
    glTF that draws no mesh and has animations (an animation library exported without its mesh,
    which ``simplify`` refuses). A file that cannot be read gets its kind's job, which says why."""
    if kind == "gltf":
        from ..io.errors import FormatError
        from ..io.gltf_document import document_json

        try:
            document = document_json(source)
        except FormatError:
            return DEFAULT_JOBS[kind]
        nodes = document.get("nodes", [])
        if document.get("animations") and not any(isinstance(node, dict) and "mesh" in node for node in nodes):
            return "motion"
    return DEFAULT_JOBS.get(kind)


@dataclass(frozen=True)
class _OneOf:
    """An option whose default is None: a value of each plain type its annotation allows
    (``int | str | None`` -> ``(0, "")``), to check values against as against a default."""

    exemplars: tuple


@dataclass(frozen=True)
class Job:
    """A named job: its function and, per input kind, the options it accepts with their defaults."""

    name: str
    path: str  # "module:function", imported where the job runs
    kinds: tuple[str, ...]  # input kinds it takes; empty: any
    option_sources: dict[str, tuple[str, ...]]  # kind -> "module:function" whose keywords are options
    # "module:function" that refuses (ValueError) values no input can take: its keywords, each the
    # manifest's value or the default of the job's first option source; the AQEM options' check is
    # check_values' own.
    value_check: str | None = None

    def function(self) -> Callable:
        return _import(self.path)

    def sources(self, kind: str) -> tuple[str, ...]:
        """The "module:attribute" paths of the functions and options classes that give its
        options for input of ``kind``."""
        return self.option_sources.get(kind, self.option_sources.get("*", (self.path,)))

    def options(self, kind: str) -> dict[str, object] | None:
        """Option name -> default for input of ``kind``; None when the job takes any keyword."""
        accepted: dict[str, object] = {}
        for source in self.sources(kind):
            found = _source_options(source)
            if found is None:
                return None
            accepted.update(found)
        return accepted


# The AQEM options a pipeline passes on to simplify_animated (its keywords are this class's fields).
_AQEM = "animlod.options:AqemOptions"
# The settings the glTF pipelines share, as keywords.
_DRAWABLE = "animlod.pipelines.drawable_levels:DrawableSettings"
# The core's check of AQEM's options, the mesh-independent part of what simplify_animated refuses.
_CHECK_AQEM = "animlod.aqem:check_aqem_options"
BUILTIN_JOBS = {
    "simplify": Job(
        "simplify",
        "animlod.pipelines.assets:simplify_asset",
        ("gltf", "npz", "sequence"),
        {
            "gltf": ("animlod.pipelines.lod_document:simplify_document", _DRAWABLE, _AQEM),
            "npz": ("animlod.pipelines.lod_sequence:simplify_sequence", _AQEM),
            "sequence": ("animlod.pipelines.lod_sequence:simplify_sequence", _AQEM),
        },
    ),
    "character": Job(
        "character",
        "animlod.pipelines.assets:character_asset",
        ("gltf",),
        {"gltf": ("animlod.pipelines.character:build_character", _DRAWABLE, _AQEM)},
    ),
    "face": Job(
        "face",
        "animlod.pipelines.assets:face_asset",
        ("gltf", "sequence"),
        {"*": ("animlod.face_lod.pipeline:run_face_lod",)},
        "animlod.face_lod.pipeline:check_face_options",
    ),
    "motion": Job(
        "motion",
        "animlod.pipelines.motion:motion_asset",
        ("bvh", "gltf"),
        {"*": ("animlod.pipelines.motion:build_motion_levels",)},
        "animlod.pipelines.motion:check_motion_options",
    ),
}


def find_job(name: str) -> Job:
    """The built-in job ``name``, or a custom job ``"module:function"`` (imported here, so that
    a typo is found before anything runs). Raises ValueError naming the job."""
    if name in BUILTIN_JOBS:
        return BUILTIN_JOBS[name]
    if ":" not in name:
        raise ValueError(f"job {name!r}: unknown; built-in jobs are {', '.join(BUILTIN_JOBS)}, or 'module:function'")
    try:
        function = _import(name)
    except (ImportError, AttributeError) as error:
        raise ValueError(f"job {name!r}: cannot be imported ({error})") from None
    if not callable(function):
        raise ValueError(f"job {name!r}: not a function")
    return Job(name, name, (), {})


def check_options(job: Job, kind: str, options: dict[str, object]) -> str | None:
    """Why ``options`` do not suit ``job`` on input of ``kind`` (the first problem, naming the
    option), or None when they do. Types are checked against each option's default."""
    if job.kinds and kind not in job.kinds:
        return f"job {job.name} does not take {kind} input (it takes {', '.join(job.kinds)})"
    accepted = job.options(kind)
    if accepted is None:
        return None
    for name, value in options.items():
        if name not in accepted:
            known = ", ".join(sorted(accepted))
            return f"option {name!r}: unknown for job {job.name} on {kind} input (known: {known})"
        problem = _type_problem(value, accepted[name])
        if problem:
            return f"option {name!r}: {problem}"
    return None


def check_values(job: Job, kind: str, options: dict[str, object]) -> str | None:
    """Why the values of ``options`` (of the types :func:`check_options` checks) would stop
    ``job`` on input of ``kind``, naming the option, or None. Asked of the code that refuses them
    as the job runs, so that no range is written twice: the glTF pipelines' settings are resolved
    from them, the core's check of AQEM's options (``ratios``, which every job with AQEM levels
    passes on as its target_ratios, ``max_error`` and the rest) that needs no mesh, and the job's
    ``value_check`` (the motion and face pipelines' own)."""
    sources = job.sources(kind)

    def taken_by(source: str) -> dict[str, object]:
        return {name: value for name, value in options.items() if name in _source_options(source)}

    try:
        if job.value_check is not None:
            check = _import(job.value_check)
            defaults = inspect.signature(_import(sources[0])).parameters
            check(**{name: options.get(name, defaults[name].default) for name in inspect.signature(check).parameters})
        if _DRAWABLE in sources:
            _import(_DRAWABLE).resolve(None, taken_by(_DRAWABLE))
        if _AQEM in sources:
            _import(_CHECK_AQEM)(options.get("ratios"), **taken_by(_AQEM))
    except ValueError as error:
        return " ".join(str(error).split())
    return None


class _Kind(typing.NamedTuple):
    """A plain type an option takes: its Python type, what the messages call a value of it, and
    whether a value is one."""

    type: type
    name: str
    fits: Callable[[object], bool]


def _number(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and not math.isnan(value)


# The kinds of value an option's default can be, bool before int (a bool is an int), str before
# the lists (a str is a Sequence). The one place that names them, for a default and a _OneOf alike.
_KINDS = (
    _Kind(bool, "true or false", lambda value: isinstance(value, bool)),
    _Kind(int, "a whole number", lambda value: isinstance(value, int) and not isinstance(value, bool)),
    _Kind(float, "a number", _number),
    _Kind(str, "a string", lambda value: isinstance(value, str)),
    _Kind(Sequence, "a list", lambda value: isinstance(value, (list, tuple))),
)


def _kind(default: object) -> _Kind | None:
    """The kind of ``default``; None for another type, whose values are not checked."""
    return next((kind for kind in _KINDS if isinstance(default, kind.type)), None)


def _type_problem(value: object, default: object) -> str | None:
    """What is wrong with ``value`` for an option whose default is ``default`` (None if nothing)."""
    if default is None or default is inspect.Parameter.empty:
        return None
    if isinstance(default, _OneOf):
        if value is None:
            return None
        kinds = [_kind(exemplar) for exemplar in default.exemplars]
        fitting = [exemplar for exemplar, kind in zip(default.exemplars, kinds) if kind is None or kind.fits(value)]
        if not fitting:
            return f"expected {' or '.join(kind.name for kind in kinds)}, got {value!r}"
        problems = [_type_problem(value, exemplar) for exemplar in fitting]
        return None if None in problems else problems[0]  # a list of the right kind, but an item of another
    kind = _kind(default)
    if kind is None:
        return None
    if not kind.fits(value):
        return f"expected {kind.name}, got {value!r}"
    if kind.type is Sequence and default:
        for item in value:
            problem = _type_problem(item, default[0])
            if problem:
                return f"in the list: {problem}"
    return None


def _keywords(function: Callable) -> dict[str, object] | None:
    """Keyword parameters of ``function`` (name -> default) but the reserved ones; None when it
    takes ``**kwargs`` (anything goes)."""
    accepted = {}
    for parameter in inspect.signature(function, eval_str=True).parameters.values():
        if parameter.kind is inspect.Parameter.VAR_KEYWORD:
            if function.__module__.startswith("animlod."):
                continue  # the pipeline's AQEM keywords: listed by the AqemOptions source
            return None
        if parameter.kind in (inspect.Parameter.VAR_POSITIONAL, inspect.Parameter.POSITIONAL_ONLY):
            continue
        alternatives = _alternatives(parameter.annotation)
        callback = any(typing.get_origin(kind) is collections.abc.Callable for kind in alternatives)
        if parameter.name in _RESERVED or parameter.name.startswith("_") or callback:
            continue
        if parameter.default is inspect.Parameter.empty and parameter.kind is not inspect.Parameter.KEYWORD_ONLY:
            continue  # the positional inputs (source, output, mesh)
        default = parameter.default
        if default is None:
            exemplars = [_exemplar(kind) for kind in alternatives if kind is not type(None)]
            default = _OneOf(tuple(exemplars)) if exemplars and None not in exemplars else None
        elif isinstance(default, (list, tuple)) and not default:  # no item to check others against
            default = _exemplar(parameter.annotation) or default
        accepted[parameter.name] = default
    return accepted


def _alternatives(annotation: object) -> tuple:
    """The types of a union annotation (``int | None`` -> ``(int, NoneType)``), else itself."""
    if typing.get_origin(annotation) in (typing.Union, types.UnionType):
        return typing.get_args(annotation)
    return (annotation,)


def _exemplar(annotation: object) -> object:
    """A value of the plain type ``annotation`` (a number, a string, a list of them) to check
    values against; None for any other type, whose values are not checked."""
    if annotation in (bool, int, float, str):
        return annotation()
    if typing.get_origin(annotation) in (list, tuple, collections.abc.Sequence):
        items = [_exemplar(item) for item in typing.get_args(annotation) if item is not Ellipsis]
        return [items[0]] if items and items[0] is not None else []
    return None


def _option_fields(options_type: type) -> dict[str, object]:
    """Fields of a bound options class and of its nested options (name -> default) that hold a
    plain value; the lists (level targets, frame subsets) are the pipeline's to fill in."""
    defaults = options_type()
    found: dict[str, object] = {}
    for name in options_type.fields:
        value = getattr(defaults, name)
        if hasattr(type(value), "fields"):
            found.update(_option_fields(type(value)))
        elif isinstance(value, (bool, int, float, str)):
            found[name] = value
    return found


@functools.cache  # signatures and options classes do not change while a process runs
def _source_options(source: str) -> dict[str, object] | None:
    """Option name -> default of one option source: a function's keywords (None when it takes any)
    or a bound options class's fields."""
    imported = _import(source)
    return _option_fields(imported) if hasattr(imported, "fields") else _keywords(imported)


def _import(path: str) -> Callable:
    module, _, attribute = path.partition(":")
    return getattr(importlib.import_module(module), attribute)
