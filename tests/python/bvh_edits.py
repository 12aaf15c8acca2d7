"""BVH files built from others for tests."""

from __future__ import annotations

from pathlib import Path


def with_a_second_root(source: Path, target: Path, renames: dict[str, str]) -> Path:
    """``source`` (a BVH of one ROOT) with a copy of its hierarchy as a second ROOT, its names
    changed by ``renames`` (text replacements), moving as the first: every row written twice."""
    hierarchy, table = source.read_text().split("MOTION\n")
    second = hierarchy.split("HIERARCHY\n", 1)[1]
    for old, new in renames.items():
        second = second.replace(old, new)
    header, rows = table.splitlines()[:2], table.splitlines()[2:]
    target.write_text(hierarchy + second + "MOTION\n" + "\n".join(header + [f"{row} {row}" for row in rows]) + "\n")
    return target
