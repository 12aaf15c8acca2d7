"""One error form for every reader and writer: ``FILE: ELEMENT: REASON`` as a ValueError.

The command line prints every user-facing error as one line ``animlod CMD: error: WHERE: WHAT``
(:func:`error_line`), where WHERE names the file (input or output) and the element.
"""

from __future__ import annotations

import os


class FormatError(ValueError):
    """Raised for input that cannot be read; the message names the file, the element and the reason."""

    def __init__(self, path: str | os.PathLike, element: str, reason: str) -> None:
        self.path = os.fspath(path)
        self.element = element
        self.reason = reason
        super().__init__(f"{self.path}: {element}: {reason}")


def error_line(error: BaseException, source: str | None = None) -> str:
    """``WHERE: WHAT`` for ``error``, on one line.

    - FormatError and messages that already start with a path: as they are.
    - OSError: ``FILE: what the system said`` (``out/taken: File exists``), both files for a
      rename, or the operation when the system named no file.
    - Other ValueErrors (the data model's and the core's checks name the element, not the
      file): ``source: message``, ``source`` being the input file the command was reading.
    Newlines inside the message become spaces.
    """
    blocking = _file_in_the_way(error)
    if blocking is not None:
        message = f"{blocking}: is a file where the output needs a folder"
    elif isinstance(error, OSError):
        reason = error.strerror or str(error)
        files = [os.fspath(name) for name in (error.filename, error.filename2) if name is not None]
        message = f"{' -> '.join(files)}: {reason}" if files else f"{source or 'output'}: {reason}"
    else:
        message = str(error) or type(error).__name__
        if source and not isinstance(error, FormatError) and not _names_a_path(message, source):
            message = f"{source}: {message}"
    return " ".join(message.split())


def _file_in_the_way(error: BaseException) -> str | None:
    """The file standing where a folder was to be made (``-o out.glb`` for a command that writes
    folders), for the system's "File exists" and "Not a directory"; None for any other error."""
    from .atomic import nearest_existing

    if not isinstance(error, (FileExistsError, NotADirectoryError)) or error.filename is None:
        return None
    found = nearest_existing(error.filename)
    return os.fspath(found) if os.path.lexists(found) and not found.is_dir() else None


def _names_a_path(message: str, source: str) -> bool:
    """Whether ``message`` starts with ``source`` or with some path (``dir/file.ext: ...``)."""
    head = message.split(": ", 1)[0]
    return message.startswith(source) or os.sep in head or os.path.splitext(head)[1] != ""


class UnreadAttributesWarning(UserWarning):
    """Data of a mesh file that animlod does not read (an OBJ file's normals, a PLY file's vertex
    colours), so that levels written without them are no silent loss."""
