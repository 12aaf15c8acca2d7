"""pygltflib's object model built from parsed glTF JSON, type-checked, in one pass.

pygltflib decodes its classes through dataclasses_json, which resolves every field's type
hints again for every object: 1.7 s for the 7,163 objects of a Mixamo character (Xbot.glb,
1,426 accessors) before any geometry is read. It also bends wrong types silently (an index of
2.5 becomes 2, a translation "123" becomes [1.0, 2.0, 3.0]). Here each class's fields are
resolved once and every value is checked against glTF's JSON types, so a wrong one fails with
FormatError naming the file and the property (``accessors[3].count: expected an integer, got
2.5``); only labels (names, the generator) take a number as its text. Valid documents decode
to the same objects as pygltflib's decoder (tests/python/test_gltf_decode.py compares them on
every dev file), with two deliberate differences: a primitive's ``attributes`` and ``targets``
are always :class:`pygltflib.Attributes` (pygltflib leaves targets, and empty attributes, as
dicts), and ``extras`` may be any JSON value, as glTF 2.0 allows (pygltflib refuses all but
objects).
"""

from __future__ import annotations

import dataclasses
import functools
import typing
from collections.abc import Callable
from typing import Any

import pygltflib

from .errors import FormatError

_Decode = Callable[[Any, str], Any]


class _WrongType(Exception):
    """A JSON value of the wrong type at ``where`` (turned into FormatError with the file's path)."""

    def __init__(self, where: str, reason: str) -> None:
        super().__init__(where, reason)
        self.where, self.reason = where, reason


def decode_gltf(path: str, document: dict) -> pygltflib.GLTF2:
    """The :class:`pygltflib.GLTF2` of ``document`` (a glTF JSON object as ``json.loads`` gives
    it, not kept: the result shares no object with it); FormatError naming ``path`` and the
    property for a value of the wrong type or a null inside an array."""
    try:
        return _decoder(pygltflib.GLTF2)(document, "")
    except _WrongType as error:
        raise FormatError(path, error.where or "JSON", error.reason) from None


def is_whole_number(value: object) -> bool:
    """Whether a JSON value is an integer >= 0 (an index, a count, a byte offset; not a bool)."""
    return isinstance(value, int) and not isinstance(value, bool) and value >= 0


def _describe(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else f"a {type(value).__name__}"


def _integer(value: Any, where: str) -> int:
    if isinstance(value, int) and not isinstance(value, bool):
        return value
    if isinstance(value, float) and value.is_integer():  # 3.0 is an integer in JSON Schema
        return int(value)
    raise _WrongType(where, f"expected an integer, got {_describe(value)}")


def _number(value: Any, where: str) -> float:
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return float(value)
    raise _WrongType(where, f"expected a number, got {_describe(value)}")


def _string(value: Any, where: str) -> str:
    if isinstance(value, str):
        return value
    raise _WrongType(where, f"expected a string, got {_describe(value)}")


def _label(value: Any, where: str) -> str:
    """A descriptive string (a name, the generator): a number is taken as its text, as pygltflib
    does, rather than refusing a whole file over a label nothing reads."""
    if _is_number(value):
        return str(value)
    return _string(value, where)


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def labels_as_text(document: dict) -> None:
    """Numbers given as labels in a glTF JSON object (a scene named 42) become their text in place,
    as :func:`decode_gltf` takes them, so that writers copying the JSON write valid labels. Only
    the asset and the top-level objects have labels in glTF 2.0."""
    holders = [document.get("asset")] + [
        item for items in document.values() if isinstance(items, list) for item in items
    ]
    for holder in holders:
        if isinstance(holder, dict):
            for key in _LABELS:
                if _is_number(holder.get(key)):
                    holder[key] = str(holder[key])


def _boolean(value: Any, where: str) -> bool:
    if isinstance(value, bool):
        return value
    raise _WrongType(where, f"expected true or false, got {_describe(value)}")


def _json_object(value: Any, where: str) -> dict:
    if isinstance(value, dict):
        return value
    raise _WrongType(where, f"expected an object, got {_describe(value)}")


def _attributes(value: Any, where: str) -> pygltflib.Attributes:
    """A primitive's or morph target's attribute indices by name (any name: custom ones too)."""
    attributes = pygltflib.Attributes()
    for name, index in _json_object(value, where).items():
        setattr(attributes, name, _integer(index, f"{where}.{name}"))
    return attributes


_SCALARS: dict[Any, _Decode] = {int: _integer, float: _number, str: _string, bool: _boolean}
_LABELS = ("name", "generator", "copyright")


def _array_of(item: _Decode) -> _Decode:
    def decode(value: Any, where: str) -> list:
        if not isinstance(value, list):
            raise _WrongType(where, f"expected an array, got {_describe(value)}")
        decoded = []
        for index, element in enumerate(value):
            if element is None:
                raise _WrongType(f"{where}[{index}]", "null (glTF arrays hold no nulls)")
            decoded.append(item(element, f"{where}[{index}]"))
        return decoded

    return decode


def _free_json(value: Any, where: str) -> Any:
    """``extras``: any JSON value, kept as it is (copied: the result shares nothing with the input)."""
    return _copy_json(value)


def _copy_json(value: Any) -> Any:
    if isinstance(value, dict):
        return {key: _copy_json(item) for key, item in value.items()}
    if isinstance(value, list):
        return [_copy_json(item) for item in value]
    return value


def _extensions(value: Any, where: str) -> dict:
    """``extensions``: an object of objects (glTF 2.0's extension.schema.json), kept as it is."""
    extensions = _json_object(value, where)
    for name, extension in extensions.items():
        _json_object(extension, f"{where}.{name}")
    return _copy_json(extensions)


def _decoder_for_hint(hint: Any, owner: str) -> _Decode:
    """The decoder of field ``owner`` ("Class.field") of type ``hint``; TypeError for a form
    pygltflib did not use when this was written (a newer one should fail the tests, not decode
    wrongly)."""
    field_name = owner.rsplit(".", 1)[-1]
    if field_name == "extras":
        return _free_json
    if field_name == "extensions":
        return _extensions
    origin, arguments = typing.get_origin(hint), typing.get_args(hint)
    if origin is typing.Union and len(arguments) == 2 and type(None) in arguments:  # Optional[X]
        return _decoder_for_hint(next(a for a in arguments if a is not type(None)), owner)
    if origin is list and len(arguments) == 1:
        return _array_of(_decoder_for_hint(arguments[0], owner))
    if hint is pygltflib.Attributes:
        return _attributes
    if hint is str and field_name in _LABELS:
        return _label
    if hint in _SCALARS:
        return _SCALARS[hint]
    if dataclasses.is_dataclass(hint):
        return _decoder(hint)
    raise TypeError(f"pygltflib.{owner}: type {hint!r} is unknown to gltf_decode (a newer pygltflib?)")


@functools.cache
def _decoder(cls: type) -> _Decode:
    """The decoder of a pygltflib class: its fields' decoders, resolved once."""
    hints = typing.get_type_hints(cls)
    fields = dataclasses.fields(cls)
    plan = [(field, _decoder_for_hint(hints[field.name], f"{cls.__name__}.{field.name}")) for field in fields]

    def decode(value: Any, where: str) -> Any:
        properties = _json_object(value, where)
        arguments = {}
        for field, decode_field in plan:
            given = properties.get(field.name)
            if given is not None:  # null is taken as absent, as pygltflib does
                arguments[field.name] = decode_field(given, f"{where}.{field.name}".lstrip("."))
            elif field.default_factory is not dataclasses.MISSING:
                arguments[field.name] = field.default_factory()
            elif field.default is not dataclasses.MISSING:
                arguments[field.name] = field.default
            else:
                arguments[field.name] = None
        return cls(**arguments)

    return decode
