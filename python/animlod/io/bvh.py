"""BVH (Biovision Hierarchy) motion files: read and write.

A BVH file has a HIERARCHY (joints with an OFFSET, CHANNELS and children, leaves marked by
``End Site``) and a MOTION table with one row of channel values per frame.

Conventions of this reader, in terms of :class:`animlod.model.Motion`:

- Joints are kept in file order (depth first), so parents come before children. An
  ``End Site`` becomes a joint with ``skeleton.end_sites[j] = True``, named after the name
  written beside it or else ``f"{parent}_End"``, with a number appended where a joint of the
  file has that name (``A_End1`` beside a JOINT ``A_End``, wherever that joint is written).
- ``skeleton.offsets`` are the OFFSET values; the root's offset is its rest position.
- A file with several ROOTs (two performers, a tracked prop) is one skeleton: a joint named
  ``Roots`` at the origin, without channels, holds each ROOT as a child, whose position channels
  become its ``joint_translations`` (:func:`write_bvh` writes it back with one ROOT).
- Position channels *replace* the offset of their joint. The root's become
  ``root_positions`` (the root's OFFSET when it has none). Position channels on other joints
  (Bandai Namco files put six channels on every joint, and animate the hips' translation under
  a static root) become ``Motion.joint_translations`` when they differ from the OFFSET in any
  frame, so forward kinematics matches the file exactly; otherwise it stays None.
- Rotation channels are intrinsic Euler angles in degrees, in the order the channels are
  written (``Zrotation Xrotation Yrotation`` means ``R = Rz @ Rx @ Ry``), per joint. A joint
  may have fewer than three (a hinge's ``CHANNELS 1 Xrotation``): it does not turn about the
  others; position channels too may be any of the three.
- Keywords (``HIERARCHY``, ``ROOT``, ``JOINT``, ``OFFSET``, ``CHANNELS``, ``End Site``,
  ``MOTION``, ``Frames:``, ``Frame Time:``) are matched regardless of ASCII case, as Blender's
  importer matches them (some exporters write ``hierarchy``, ``root``, ``offset``); channel
  names too (``xrotation``). Joint names are kept as written, and stay case-sensitive.
- Text is UTF-8 (a byte order mark is skipped), or UTF-16 with a byte order mark; a file that is
  neither has its joint names in a legacy code page, read as Shift-JIS or else Latin-1
  (:func:`_decode`). Files are written in UTF-8.
- ``Frame Time`` gives fps; when the written frame time is an integer rate rounded to the digits
  written (``.0083333`` for 120 fps), fps is that integer.
"""

from __future__ import annotations

import os
import re
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from decimal import Decimal
from pathlib import Path

import numpy as np

from .. import rotations
from ..model import Motion, Skeleton
from .atomic import atomic_write
from .errors import FormatError
from .tokens import parses, tokens_per_line

# The joint a file with several ROOTs gets above them (a number appended if the file uses the name).
ROOTS_JOINT = "Roots"
# Lower-case channel name -> (kind, axis index).
_CHANNELS = {
    f"{axis.lower()}{kind}": (kind, index) for index, axis in enumerate("XYZ") for kind in ("position", "rotation")
}


def _any_case(keyword: str) -> str:
    """A regular expression matching ``keyword`` in any ASCII case (re.IGNORECASE would also take
    Unicode look-alikes: the long s for "s", the Kelvin sign for "k")."""
    return "".join(f"[{char.upper()}{char.lower()}]" if char.isalpha() else re.escape(char) for char in keyword)


def _is_keyword(token: str, keyword: str) -> bool:
    """Whether ``token`` is the upper-case ``keyword`` written in any ASCII case."""
    return token.isascii() and token.upper() == keyword


_MOTION_LINE = re.compile(rf"^[ \t]*{_any_case('MOTION')}\b", re.MULTILINE)
_FRAMES_LINE = re.compile(rf"\s*{_any_case('Frames:')}\s*(\d+)\s*")
_FRAME_TIME_LINE = re.compile(rf"\s*{_any_case('Frame')}\s+{_any_case('Time:')}\s*(\S+)\s*")
# Largest magnitude of an OFFSET or channel value. Beyond it, squared distances in forward
# kinematics and error measures overflow (an OFFSET of 1e300 gave infinite errors and exit 0);
# 1e12 is a million kilometres in millimetres, or 10^12 degrees.
MAX_VALUE = 1e12


@dataclass
class _JointSpec:
    """One joint as written in the HIERARCHY section."""

    name: str
    parent: int
    end_site: bool
    offset: tuple[float, float, float] | None = None
    channels: list[str] = field(default_factory=list)


class _TokenCursor:
    """Whitespace-separated tokens of the HIERARCHY section, each with its 1-based line number."""

    def __init__(self, path: Path, lines: list[str]) -> None:
        self.path = path
        self.lines = lines
        found = [(match, number) for number, line in enumerate(lines, start=1) for match in re.finditer(r"\S+", line)]
        self.tokens = [(match.group(), number) for match, number in found]
        self.spans = [match.span() for match, _ in found]  # where each token stands on its line
        self.position = 0
        self.last_line = len(lines)

    def error(self, line: int, reason: str) -> FormatError:
        return FormatError(self.path, f"line {line}", reason)

    def peek(self) -> tuple[str, int] | None:
        return self.tokens[self.position] if self.position < len(self.tokens) else None

    def next(self, expected: str) -> tuple[str, int]:
        token = self.peek()
        if token is None:
            raise self.error(self.last_line, f"file ends where {expected} was expected")
        self.position += 1
        return token

    def expect(self, literal: str) -> None:
        """Consume ``literal`` (a keyword in any ASCII case, or a brace)."""
        token, line = self.next(repr(literal))
        if not _is_keyword(token, literal.upper()):
            raise self.error(line, f"expected {literal!r}, found {token!r}")

    def number(self, what: str) -> float:
        token, line = self.next(what)
        try:
            value = float(token)
        except ValueError:
            raise self.error(line, f"{what}: {token!r} is not a number") from None
        if not np.isfinite(value):
            raise self.error(line, f"{what}: value {token} is not finite")
        if abs(value) > MAX_VALUE:
            raise self.error(line, f"{what}: value {token} is beyond +-{MAX_VALUE:g}")
        return value

    def rest_of_line(self, line: int) -> str:
        """The text of the tokens left on ``line`` up to an opening brace, as written between them
        (joint names may hold spaces: "Left  Shoulder" stays as it is)."""
        first = self.position
        while (token := self.peek()) is not None and token[1] == line and token[0] != "{":
            self.next("name")
        if self.position == first:
            return ""
        return self.lines[line - 1][self.spans[first][0] : self.spans[self.position - 1][1]]


def read_bvh(path: str | os.PathLike) -> Motion:
    """Read a BVH file into a :class:`~animlod.model.Motion` (conventions in the module docstring).

    Parameters
    ----------
    path : the .bvh file; LF, CRLF and mixed line endings are accepted.

    Returns
    -------
    Motion with ``local_rotations (T, J, 4)``, ``root_positions (T, 3)``, fps from Frame Time,
    the file's stem as name, and ``joint_translations (T, J, 3)`` when non-root position
    channels move their joints away from their offsets.

    Raises
    ------
    FormatError
        Naming the file, the line, joint or frame, and the reason: a malformed hierarchy, a
        MOTION table with fewer rows than ``Frames:``, a row with the wrong number of
        values, a value that is not a finite number. A table with more whole rows than ``Frames:``
        says is read whole, with a warning.
    """
    return read_bvh_with_layout(path)[0]


@dataclass(frozen=True)
class BvhLayout:
    """What a BVH file's hierarchy says besides the motion :func:`read_bvh` makes of it.

    roots : names of its ROOT joints in file order (several: :func:`read_bvh` puts them under one
        joint of its own, :data:`ROOTS_JOINT`).
    rotation_orders : joint name -> Euler order of its rotation channels as written (``"ZYX"``
        for ``Zrotation Yrotation Xrotation``), for the joints with all three: what
        :func:`write_bvh` takes to write a motion in the file's own channel layout.
    """

    roots: list[str]
    rotation_orders: dict[str, str]


def read_bvh_with_layout(path: str | os.PathLike) -> tuple[Motion, BvhLayout]:
    """:func:`read_bvh` and the file's :class:`BvhLayout`, from one read of the file."""
    path = Path(path)
    text, joints, roots, motion_match, motion_line = _read_hierarchy(path)
    if motion_match is None:
        raise FormatError(path, f"line {motion_line}", "no MOTION section after the hierarchy")
    frame_count, fps, data_line, data_text = _parse_motion_header(path, text[motion_match.end() :], motion_line)
    channel_count = sum(len(joint.channels) for joint in joints)
    values = _parse_motion_table(path, data_text, data_line, frame_count, channel_count, joints)
    orders = {joint.name: order for joint in joints if sorted(order := _rotation_order(joint)) == ["X", "Y", "Z"]}
    return _build_motion(path, joints, values, fps), BvhLayout([joints[root].name for root in roots], orders)


def _rotation_order(joint: _JointSpec) -> str:
    """The axes of ``joint``'s rotation channels in the order they are written (``"ZXY"``)."""
    return "".join("XYZ"[axis] for kind, axis in (_CHANNELS[channel.lower()] for channel in joint.channels)
                   if kind == "rotation")  # fmt: skip


def _read_hierarchy(path: Path) -> tuple[str, list[_JointSpec], list[int], re.Match | None, int]:
    """The file's text (line ends made LF), its parsed joints and the indices of its ROOTs among
    them (:func:`_parse_hierarchy`), the match of its MOTION line (None when it has none) and the
    number of lines before it."""
    text = _decode(path.read_bytes()).replace("\r\n", "\n").replace("\r", "\n")
    motion_match = _MOTION_LINE.search(text)
    hierarchy_lines = text[: motion_match.start() if motion_match else len(text)].split("\n")
    joints, roots = _parse_hierarchy(_TokenCursor(path, hierarchy_lines))
    return text, joints, roots, motion_match, len(hierarchy_lines)


def _decode(data: bytes) -> str:
    """The text of a BVH file: UTF-8 (a byte order mark dropped), UTF-16 after its byte order mark
    (PowerShell's ``>`` and Notepad's "Unicode" write it), else the legacy code page the joint
    names were written in: Shift-JIS (cp932, MikuMikuDance converters) when the bytes decode as
    it into no half-width katakana, Latin-1 otherwise. Only names are outside ASCII, and a strict
    decoding keeps different names different (replacing undecodable bytes made 左足 and 右足 one
    name, "\ufffd\ufffd", written twice)."""
    if data.startswith((b"\xff\xfe", b"\xfe\xff")):
        return data.decode("utf-16", errors="replace")  # an odd byte at the end: a truncated file
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        pass
    try:
        text = data.decode("cp932")
    except UnicodeDecodeError:
        return data.decode("latin-1")
    return data.decode("latin-1") if re.search("[\uff61-\uff9f]", text) else text


def _parse_hierarchy(cursor: _TokenCursor) -> tuple[list[_JointSpec], list[int]]:
    """Joints in file order, under a joint of their own (:data:`ROOTS_JOINT`) when the file has
    several ROOTs, and the indices of the file's ROOTs among them."""
    cursor.expect("HIERARCHY")
    token, line = cursor.next("ROOT")
    if not _is_keyword(token, "ROOT"):
        raise cursor.error(line, f"expected ROOT, found {token!r}")
    joints: list[_JointSpec] = []
    roots = []
    while True:
        roots.append(len(joints))
        _parse_root(cursor, joints, line)
        extra = cursor.peek()
        if extra is None:
            break
        if not _is_keyword(extra[0], "ROOT"):
            raise cursor.error(extra[1], f"unexpected {extra[0]!r} after the root")
        line = cursor.next("ROOT")[1]
    if len(roots) == 1:
        return joints, roots
    # Several ROOTs (performers, props): one skeleton, each root a translating joint below a
    # joint at the origin, which has no channels.
    for joint in joints:
        joint.parent += 1
    for root in roots:
        joints[root].parent = 0
    above = _JointSpec(_unique_name(ROOTS_JOINT, joints), -1, False, (0.0, 0.0, 0.0))
    return [above, *joints], [root + 1 for root in roots]


def _parse_root(cursor: _TokenCursor, joints: list[_JointSpec], line: int) -> None:
    """One ROOT block (keyword consumed), its joints appended in file order. Iterative, with a
    stack of open blocks: chains of any depth parse."""
    open_blocks = [_open_joint(cursor, joints, parent=-1, line=line, end_site=False)]  # (joint, line)
    while open_blocks:
        index, opened = open_blocks[-1]
        joint = joints[index]
        token, token_line = cursor.next(f"'}}' closing joint {joint.name!r} (opened on line {opened})")
        if token == "}":
            if joint.offset is None:
                raise cursor.error(opened, f"joint {joint.name!r} has no OFFSET")
            open_blocks.pop()
        elif _is_keyword(token, "OFFSET"):
            joint.offset = tuple(cursor.number(f"OFFSET of joint {joint.name!r}") for _ in range(3))
        elif _is_keyword(token, "CHANNELS") and not joint.end_site:
            joint.channels = _parse_channels(cursor, joint.name, token_line)
        elif _is_keyword(token, "JOINT") and not joint.end_site:
            open_blocks.append(_open_joint(cursor, joints, index, token_line, end_site=False))
        elif _is_keyword(token, "END") and not joint.end_site:
            cursor.expect("Site")
            open_blocks.append(_open_joint(cursor, joints, index, token_line, end_site=True))
        else:
            where = f"End Site of {joints[joint.parent].name!r}" if joint.end_site else f"joint {joint.name!r}"
            raise cursor.error(token_line, f"unexpected {token!r} in {where}")


def _open_joint(
    cursor: _TokenCursor, joints: list[_JointSpec], parent: int, line: int, end_site: bool
) -> tuple[int, int]:
    """Read the name and ``{`` of a ROOT / JOINT / End Site (keyword consumed); append the joint.

    Returns the new joint's index and the line that opened it.
    """
    name = cursor.rest_of_line(line)
    if end_site:
        name = _unique_name(name or f"{joints[parent].name}_End", joints)
    elif not name:
        raise cursor.error(line, "joint without a name")
    elif (taken := next((joint for joint in joints if joint.name == name), None)) is not None:
        if not taken.end_site:
            raise cursor.error(line, f"joint name {name!r} is used twice")
        # An end site's name is the reader's (BVH writes none back); the joint keeps its own.
        taken.name = _unique_name(name, joints)
    cursor.expect("{")
    joints.append(_JointSpec(name, parent, end_site))
    return len(joints) - 1, line


def _parse_channels(cursor: _TokenCursor, joint_name: str, line: int) -> list[str]:
    count_token, _ = cursor.next("channel count")
    if not (count_token.isascii() and count_token.isdigit()):  # "²".isdigit() is True, int("²") fails
        raise cursor.error(line, f"joint {joint_name!r}: channel count {count_token!r} is not a whole number")
    channels = [cursor.next(f"channel name of joint {joint_name!r}")[0] for _ in range(int(count_token))]
    unknown = [channel for channel in channels if channel.lower() not in _CHANNELS]
    if unknown:
        raise cursor.error(line, f"joint {joint_name!r}: unknown channel {unknown[0]!r}")
    lowered = [channel.lower() for channel in channels]
    if len(set(lowered)) != len(lowered):
        raise cursor.error(line, f"joint {joint_name!r}: channels {channels} must name each axis once")
    return channels


def _unique_name(name: str, joints: list[_JointSpec]) -> str:
    taken = {joint.name for joint in joints}
    candidate, suffix = name, 1
    while candidate in taken:
        candidate, suffix = f"{name}{suffix}", suffix + 1
    return candidate


def _parse_motion_header(path: Path, text: str, motion_line: int) -> tuple[int, float, int, str]:
    """Read ``Frames:`` and ``Frame Time:`` after MOTION, blank lines around them skipped (a file
    converted to CRLF twice, CR CR LF, has one after every line).

    Returns the frame count, the frame rate, the line number of the first row and the rows' text.
    """
    header: list[tuple[int, str]] = []  # (line, text) of the two lines
    line, position = motion_line, text.find("\n") + 1  # position 0: no line left
    while len(header) < 2 and position > 0:
        end = text.find("\n", position)
        row = text[position:] if end < 0 else text[position:end]
        line, position = line + 1, end + 1
        if row.strip():
            header.append((line, row))
    if len(header) < 2:
        raise FormatError(path, f"line {motion_line}", "MOTION is not followed by Frames: and Frame Time: lines")
    (frames_line, frames_text), (time_line, time_text) = header
    frames_match = _FRAMES_LINE.fullmatch(frames_text)
    if frames_match is None:
        raise FormatError(path, f"line {frames_line}", f"expected 'Frames: N', found {_quoted(frames_text)}")
    time_match = _FRAME_TIME_LINE.fullmatch(time_text)
    frame_time = float(time_match.group(1)) if time_match and parses(time_match.group(1), np.float64) else None
    # The rate 1 / Frame Time must be finite too: Frame Time: 1e-320 is positive but its inverse is not.
    if frame_time is None or not (frame_time > 0.0 and np.isfinite(frame_time) and np.isfinite(1.0 / frame_time)):
        reason = f"expected 'Frame Time: SECONDS' > 0 with a finite frame rate, found {_quoted(time_text)}"
        raise FormatError(path, f"line {time_line}", reason)
    frame_count = int(frames_match.group(1))
    if frame_count < 1:
        raise FormatError(path, f"line {frames_line}", "Frames: must be at least 1")
    return frame_count, _frame_rate(time_match.group(1)), line + 1, text[position:] if position > 0 else ""


def _quoted(line: str) -> str:
    """A line quoted in a message, cut after 60 characters (a frame's row can hold thousands)."""
    line = line.strip()
    return repr(line) if len(line) <= 60 else f"{line[:60]!r}... ({len(line)} characters)"


def _frame_rate(frame_time: str) -> float:
    """Frames per second for a written frame time, snapped to the integer rate it was rounded from."""
    seconds = float(frame_time)
    # Digits after the point as written, in scientific notation too: 8.333333e-03 has 9.
    decimals = -int(Decimal(frame_time).as_tuple().exponent)
    rate = 1.0 / seconds
    whole = round(rate)
    if whole >= 1 and abs(seconds - 1.0 / whole) <= 0.5 * 10.0**-decimals:
        return float(whole)
    return rate


def _parse_motion_table(
    path: Path, text: str, first_line: int, frame_count: int, channel_count: int, joints: list[_JointSpec]
) -> np.ndarray:
    """Channel values ``(T, C)`` of the MOTION rows, checked row by row against the hierarchy."""
    if channel_count == 0:  # every row empty: read as no row, "truncated" misled
        raise FormatError(path, "HIERARCHY", "no joint has channels (every CHANNELS is 0): the file holds no motion")
    counts = tokens_per_line(text.encode("utf-8"))
    rows = np.nonzero(counts)[0]  # blank lines are skipped
    wrong = rows[counts[rows] != channel_count]
    if wrong.size:
        row = int(np.searchsorted(rows, wrong[0]))
        raise FormatError(
            path,
            f"line {first_line + wrong[0]} (frame {row})",
            f"expected {channel_count} channel values, found {counts[wrong[0]]}",
        )
    if rows.size < frame_count:
        reason = f"Frames: says {frame_count} but the MOTION table has {rows.size} rows (truncated file?)"
        raise FormatError(path, f"line {first_line + (rows[-1] + 1 if rows.size else 0)} (frame {rows.size})", reason)
    if rows.size > frame_count:
        # Some exporters count one frame short (the assimp test set's Boxing_Toes.bvh: 3069 for
        # 3070 rows); every row is whole and checked, so none is dropped, as Blender reads them.
        reason = f"Frames: says {frame_count} but the MOTION table has {rows.size} rows; read all {rows.size}"
        warnings.warn(f"{path}: {reason}", stacklevel=4)
        frame_count = int(rows.size)
    owners = [(joint.name, channel) for joint in joints for channel in joint.channels]

    def value_error(flat_index: int, reason: str) -> FormatError:
        frame, column = divmod(flat_index, channel_count)
        joint_name, channel = owners[column]
        element = f"line {first_line + rows[frame]} (frame {frame}), joint {joint_name!r} {channel}"
        return FormatError(path, element, reason)

    # Split on the ASCII whitespace tokens_per_line counted: str.split() also splits on Unicode
    # separators such as U+00A0, which would shift the values against the checked row lengths.
    tokens = np.array(text.encode("utf-8").split(), dtype=np.bytes_)
    try:
        values = tokens.astype(np.float64).reshape(frame_count, channel_count)
    except ValueError:
        bad = next(index for index, token in enumerate(tokens) if not parses(token, np.float64))
        raise value_error(bad, f"{tokens[bad].decode(errors='replace')!r} is not a number") from None
    finite = np.isfinite(values)
    if not finite.all():
        bad = int(np.argmin(finite.ravel()))
        raise value_error(bad, f"value {values.flat[bad]} is not finite")
    huge = np.abs(values) > MAX_VALUE
    if huge.any():
        bad = int(np.argmax(huge.ravel()))
        raise value_error(bad, f"value {values.flat[bad]:g} is beyond +-{MAX_VALUE:g}")
    return values


def _build_motion(path: Path, joints: list[_JointSpec], values: np.ndarray, fps: float) -> Motion:
    """Turn channel values ``(T, C)`` into root positions, local rotations and joint translations."""
    joint_count = len(joints)
    offsets = np.array([joint.offset for joint in joints], dtype=np.float64)
    translations = np.repeat(offsets[None], values.shape[0], axis=0)
    local_rotations = rotations.identity((values.shape[0], joint_count))
    position_columns: list[tuple[int, int, int]] = []  # (joint, axis, column)
    rotation_columns: dict[str, list[tuple[int, list[int]]]] = {}  # Euler order -> [(joint, columns)]
    column = 0
    for index, joint in enumerate(joints):
        columns = []
        for channel in joint.channels:
            kind, axis = _CHANNELS[channel.lower()]
            if kind == "position":
                position_columns.append((index, axis, column))
            else:
                columns.append(column)
            column += 1
        if columns:
            rotation_columns.setdefault(_rotation_order(joint), []).append((index, columns))
    if position_columns:
        joint_index, axis, source = np.array(position_columns).T
        translations[:, joint_index, axis] = values[:, source]
    # One vectorised conversion per Euler order present in the file (at most six).
    for order, entries in rotation_columns.items():
        joint_index = np.array([entry[0] for entry in entries])
        angles = np.radians(values[:, np.array([entry[1] for entry in entries])])
        local_rotations[:, joint_index] = rotations.from_euler(angles, order)
    moved = np.any(translations[:, 1:] != offsets[None, 1:])
    skeleton = Skeleton(
        [joint.name for joint in joints],
        np.array([joint.parent for joint in joints]),
        offsets,
        end_sites=np.array([joint.end_site for joint in joints]),
    )
    return Motion(
        skeleton,
        translations[:, 0],
        local_rotations,
        fps,
        name=path.stem,
        joint_translations=translations if moved else None,
    )


def write_bvh(
    path: str | os.PathLike,
    motion: Motion,
    rotation_order: str | Mapping[str, str] = "ZXY",
    precision: int | None = None,
) -> None:
    """Write ``motion`` as a BVH file, atomically.

    The root gets six channels (position, then rotation), other joints three rotation channels,
    plus three position channels where ``motion.joint_translations`` moves them away from their
    offsets. End-site joints are written as ``End Site`` blocks
    (their names are not stored; :func:`read_bvh` names them ``f"{parent}_End"``). A leaf that
    is not an end site is written as a JOINT without children. ``skeleton.rest_rotations`` are
    not written: Motion's forward kinematics does not use them.

    Parameters
    ----------
    path : destination file.
    motion : the motion to write.
    rotation_order : Euler order of the rotation channels, three different axes, e.g. "ZXY"; or
        one per joint name (the :class:`BvhLayout` of the file the motion came from),
        "ZXY" for joints it does not name.
    precision : digits after the decimal point for offsets and channel values; None: 6, and
        more for a skeleton whose longest bone is under 1 unit (1e-6 of that bone at least).

    Raises
    ------
    ValueError
        For an unsupported ``rotation_order``, an end site whose translation is animated, or a
        motion whose joints scale (BVH has no scale channels).
    """
    skeleton = motion.skeleton
    named = rotation_order if isinstance(rotation_order, Mapping) else {}
    default = "ZXY" if isinstance(rotation_order, Mapping) else rotation_order
    orders = [named.get(name, default).upper() for name in skeleton.names]
    for order in {*orders, default.upper()}:
        if len(order) != 3 or set(order) != set("XYZ"):
            raise ValueError(f"{os.fspath(path)}: rotation_order: must be a permutation of XYZ, got {order!r}")
    try:
        motion.require_rigid("BVH")
    except ValueError as error:
        raise ValueError(f"{os.fspath(path)}: {error}") from None
    if precision is None:
        longest = float(np.abs(skeleton.offsets[1:]).max(initial=0.0))
        precision = max(6, 6 - int(np.floor(np.log10(longest)))) if longest > 0.0 else 6
    translations = motion.local_translations()
    has_position = np.zeros(skeleton.joint_count, dtype=bool)
    has_position[0] = True
    # A translation the written digits cannot tell from the offset does not move (float noise of
    # poses composed through a node between joints: 1e-18 on every joint of the clip).
    moves = np.abs(translations[:, 1:] - skeleton.offsets[None, 1:]) > 0.5 * 10.0**-precision
    has_position[1:] = np.any(moves, axis=(0, 2))
    animated_end_sites = np.nonzero(has_position & skeleton.end_sites)[0]
    if animated_end_sites.size:
        name = skeleton.names[animated_end_sites[0]]
        reason = "is an end site with animated translation; BVH cannot store it"
        raise ValueError(f"{os.fspath(path)}: joint {name!r}: {reason}")
    rotated = ~skeleton.end_sites
    angles = np.zeros(motion.local_rotations.shape[:2] + (3,))
    for order in set(orders):  # one vectorised conversion per order, as the reader does
        joints = rotated & (np.array(orders) == order)
        angles[:, joints] = np.degrees(rotations.to_euler(motion.local_rotations[:, joints], order))
    blocks = []
    for joint in range(skeleton.joint_count):
        if has_position[joint]:
            blocks.append(translations[:, joint])
        if rotated[joint]:
            blocks.append(angles[:, joint])
    table = np.concatenate(blocks, axis=1)
    hierarchy = _hierarchy_text(skeleton, has_position, orders, precision)
    with atomic_write(path, "w", encoding="utf-8", newline="\n") as handle:
        handle.write(hierarchy)
        handle.write(f"MOTION\nFrames: {motion.frame_count}\nFrame Time: {1.0 / motion.fps:.10g}\n")
        np.savetxt(handle, table, fmt=f"%.{precision}f", delimiter=" ")


def _hierarchy_text(skeleton: Skeleton, has_position: np.ndarray, orders: list[str], precision: int) -> str:
    """The HIERARCHY section, depth first. Iterative, so chains of any depth are written."""
    children = skeleton.children()
    lines = ["HIERARCHY"]
    pending = [(0, 0, False)]  # (joint, depth, whether to close its block)
    while pending:
        joint, depth, close = pending.pop()
        indent = "\t" * depth
        if close:
            lines.append(f"{indent}}}")
            continue
        offset = " ".join(f"{value:.{precision}f}" for value in skeleton.offsets[joint])
        if skeleton.end_sites[joint]:
            lines.extend([f"{indent}End Site", f"{indent}{{", f"{indent}\tOFFSET {offset}", f"{indent}}}"])
            continue
        channels = [f"{axis}position" for axis in "XYZ"] if has_position[joint] else []
        channels += [f"{axis}rotation" for axis in orders[joint]]
        keyword = "ROOT" if joint == 0 else "JOINT"
        lines.extend(
            [
                f"{indent}{keyword} {skeleton.names[joint]}",
                f"{indent}{{",
                f"{indent}\tOFFSET {offset}",
                f"{indent}\tCHANNELS {len(channels)} {' '.join(channels)}",
            ]
        )
        pending.append((joint, depth, True))
        pending.extend((child, depth + 1, False) for child in reversed(children[joint]))
    return "\n".join(lines) + "\n"
