"""One error form for every reader and writer: ``FILE: ELEMENT: REASON`` as a ValueError."""

from __future__ import annotations

import os


class FormatError(ValueError):
    """Raised for input that cannot be read; the message names the file, the element and the reason."""

    def __init__(self, path: str | os.PathLike, element: str, reason: str) -> None:
        self.path = os.fspath(path)
        self.element = element
        self.reason = reason
        super().__init__(f"{self.path}: {element}: {reason}")
