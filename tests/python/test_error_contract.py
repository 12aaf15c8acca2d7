"""Every raise that can reach the command line carries a WHERE.

The CLI prints ``animlod CMD: error: WHERE: WHAT``; WHERE is the file and the element. Readers
raise FormatError(path, element, reason) (or a ``fail``/``error`` helper that builds one);
the data model and the core raise ValueError("ELEMENT: WHAT"), to which the CLI adds the input
file; options raise UserError("--option: WHAT"). This walks the syntax tree of the whole
package and checks every raise of a user-facing error type (and every ``_require(condition,
message)`` of the data model) against that shape.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[2] / "python" / "animlod"
# Exception types a user can cause; others (AssertionError, NotImplementedError, ...) are bugs.
USER_FACING = {
    "ValueError",
    "UserError",
    "MachineError",
    "FormatError",
    "LinAlgError",
    "OSError",
    "FileNotFoundError",
    "TypeError",
}
# Helpers that build a FormatError from (element, reason) with the document's path.
WHERE_BUILDERS = {"fail", "error", "value_error", "FormatError"}
# "ELEMENT: WHAT" or "{path}: WHAT": a short head without a sentence's colon, then ": ".
WHERE = re.compile(r"^[^\s:][^:]{0,80}: \S")

# (file relative to the package, first words of the message template): raise sites allowed
# without a WHERE, each with its reason. Sites in files other engineers own are listed until
# they fix them (see the reliability report), so that this test stays green and new ones fail.
ALLOWED = {
    ("model.py", None): "_require's own raise: its callers' messages are checked instead",
    ("model.py", "motion has {} joints, the skin's skeleton {}"): "model.py Motion/Skin part: lead's",
    ("model.py", "skeleton has no joint named {}"): "model.py Skeleton part: lead's",
    ("synth/face_animation.py", "seconds and fps must be positive"): "procedural assets: no file, not user input",
}


def _template(node: ast.AST) -> str | None:
    """A message's text with ``{}`` for each formatted value; None when it is not a literal."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return node.value
    if isinstance(node, ast.JoinedStr):
        return "".join(part.value if isinstance(part, ast.Constant) else "{}" for part in node.values)
    if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Add):
        left = _template(node.left)
        return None if left is None else left + (_template(node.right) or "{}")
    return None


def _name(call: ast.Call) -> str:
    function = call.func
    if isinstance(function, ast.Name):
        return function.id
    return function.attr if isinstance(function, ast.Attribute) else ""


def _matches(start: str | None, template: str | None) -> bool:
    """An allow-list entry's start: None for a message that is not a literal, else its first words."""
    return template is None if start is None else (template or "").startswith(start)


def _allowed(relative: str, template: str | None) -> bool:
    return any(file == relative and _matches(start, template) for file, start in ALLOWED)


def _message_sites() -> list[tuple[str, int, str, str | None]]:
    """(file, line, exception or helper, message template) of every user-facing raise."""
    sites = []
    for path in sorted(PACKAGE.rglob("*.py")):
        relative = path.relative_to(PACKAGE).as_posix()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Raise) and isinstance(node.exc, ast.Call):
                name = _name(node.exc)
                if name in WHERE_BUILDERS or name not in USER_FACING:
                    continue
                message = _template(node.exc.args[0]) if node.exc.args else None
                sites.append((relative, node.lineno, name, message))
            elif isinstance(node, ast.Call) and _name(node) == "_require" and len(node.args) == 2:
                sites.append((relative, node.lineno, "_require", _template(node.args[1])))
    return sites


def test_every_user_facing_raise_names_where() -> None:
    missing = [
        f"{file}:{line}: {name}({message!r})"
        for file, line, name, message in _message_sites()
        if not (message is not None and WHERE.match(message)) and not _allowed(file, message)
    ]
    assert not missing, "raise sites without 'WHERE: WHAT':\n" + "\n".join(missing)


def test_the_walk_sees_the_raise_sites_it_checks() -> None:
    """A control: the walk finds the known sites, and the pattern refuses a message without WHERE."""
    sites = {(file, name) for file, _, name, _ in _message_sites()}
    assert ("io/bvh.py", "ValueError") in sites and ("model.py", "_require") in sites
    assert ("cli/simplify.py", "UserError") in sites
    assert not WHERE.match("must be positive, got {}") and not WHERE.match("Singular matrix")
    assert WHERE.match("faces: face {} has an index outside [0, {})") and WHERE.match("{}: no MOTION section")


def test_allow_list_has_no_stale_entries() -> None:
    templates = {(file, message) for file, _, _, message in _message_sites()}
    for file, start in ALLOWED:
        assert any(f == file and _matches(start, m) for f, m in templates), (file, start)
