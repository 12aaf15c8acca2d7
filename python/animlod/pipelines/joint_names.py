"""What a joint's name says across exporters: the name without namespace, case and separators,
and the body side it names."""

from __future__ import annotations

import re
from collections import Counter
from collections.abc import Hashable, Sequence

# A side letter standing alone: "LThumb", "l_arm", "hand_l", "Bip01 L Thigh", "UpperArmL".
_SIDE_LETTER = r"^{0}(?=[A-Z0-9_.\- ])|^{1}(?=[_.\- ])|(?<=[_.\- ])[{0}{1}](?![A-Za-z0-9])|(?<=[a-z]){0}$"


def normalized_name(name: str) -> str:
    """``name`` without namespace (``mixamorig:``, ``Armature|``), case and separators."""
    return re.sub(r"[^0-9a-z]", "", _without_namespace(name).lower())


def split_side(name: str) -> tuple[str | None, str]:
    """'left' or 'right' where ``name`` says it (a word or a letter standing alone), else None;
    and the name without its namespace and without the word or letter that says the side."""
    base = _without_namespace(name)
    word = re.search(r"(?i)left|right", base)
    if word:
        return word.group(0).lower(), base[: word.start()] + base[word.end() :]
    for found, letter in (("left", "L"), ("right", "R")):
        letter_alone = re.search(_SIDE_LETTER.format(letter, letter.lower()), base)
        if letter_alone:
            return found, base[: letter_alone.start()] + base[letter_alone.end() :]
    return None, base


def side(name: str) -> str | None:
    """'left' or 'right' where ``name`` says it ("LeftArm", "LThumb", "hand_l", "Bip01 R Thigh"), else None."""
    return split_side(name)[0]


def unique_index(names: Sequence[Hashable]) -> dict[Hashable, int]:
    """Each name that ``names`` holds once (empty ones aside), with its index: a name several
    joints or nodes share tells none of them apart."""
    counts = Counter(names)
    return {name: index for index, name in enumerate(names) if name and counts[name] == 1}


def _without_namespace(name: str) -> str:
    return re.split(r"[:|]", name)[-1]
