"""The catalogue of a batch: one Parquet row per asset and level (one row for a failed asset).

Columns (:data:`SCHEMA`): asset, job, input, status ("ok" or "failed"), ran (false when a
rerun skipped the asset as unchanged), level, part, triangles, joints, error (asset units),
relative_error, level_seconds, seconds (the whole asset), worker, peak_rss_mb (the worker's peak
so far), fingerprint, outputs (paths relative to OUT), error_file, error_element, error_reason,
finished (UTC). Query it with anything that reads Parquet::

    import pyarrow.compute as pc
    import pyarrow.parquet as pq

    table = pq.read_table("OUT/catalogue.parquet")
    failed = table.filter(pc.field("status") == "failed")
    failed.select(["asset", "error_file", "error_element", "error_reason"]).to_pylist()

The file is rewritten whole (atomically) as assets finish and once at the end.
"""

from __future__ import annotations

import os
from datetime import datetime
from pathlib import PurePosixPath
from typing import TYPE_CHECKING

from ..io.atomic import atomic_write

if TYPE_CHECKING:
    import pyarrow as pa

COLUMNS = (
    ("asset", "string"),
    ("job", "string"),
    ("input", "string"),
    ("status", "string"),
    ("ran", "bool"),
    ("level", "int32"),
    ("part", "string"),
    ("triangles", "int64"),
    ("joints", "int32"),
    ("error", "float64"),
    ("relative_error", "float64"),
    ("level_seconds", "float64"),
    ("seconds", "float64"),
    ("worker", "string"),
    ("peak_rss_mb", "float64"),
    ("fingerprint", "string"),
    ("outputs", "list<string>"),
    ("error_file", "string"),
    ("error_element", "string"),
    ("error_reason", "string"),
    ("finished", "timestamp"),
)


def schema() -> pa.Schema:
    """The catalogue's pyarrow schema."""
    import pyarrow as pa

    types = {
        "string": pa.string(),
        "bool": pa.bool_(),
        "int32": pa.int32(),
        "int64": pa.int64(),
        "float64": pa.float64(),
        "list<string>": pa.list_(pa.string()),
        "timestamp": pa.timestamp("ms", tz="UTC"),
    }
    return pa.schema([(name, types[kind]) for name, kind in COLUMNS])


def record_rows(record: dict, ran: bool) -> list[dict]:
    """Catalogue rows of one asset record (see :func:`animlod.batch.task.run_asset`)."""
    common = {
        "asset": record["name"],
        "job": record["job"],
        "input": record["input"],
        "status": record["status"],
        "ran": ran,
        "seconds": record.get("seconds"),
        "worker": record.get("worker"),
        "peak_rss_mb": record.get("peak_rss_mb"),
        "fingerprint": record.get("fingerprint"),
        "finished": datetime.fromisoformat(record["finished"]) if record.get("finished") else None,
    }
    result, error = record.get("result"), record.get("error")
    if record["status"] != "ok" or result is None:
        error = error or {}
        return [
            {
                **common,
                "outputs": [],
                "error_file": error.get("file"),
                "error_element": error.get("element"),
                "error_reason": error.get("reason"),
            }
        ]
    outputs = [PurePosixPath(record["name"], path).as_posix() for path in result["outputs"]]
    return [
        {
            **common,
            "level": row["level"],
            "part": row["part"],
            "triangles": row["triangles"],
            "joints": row["joints"],
            "error": row["error"],
            "relative_error": row["relative_error"],
            "level_seconds": row["seconds"],
            "outputs": outputs,
        }
        for row in result["levels"]
    ]


def write_catalogue(path: str | os.PathLike, rows: list[dict]) -> None:
    """Write ``rows`` (dicts with any of the columns; the others are null) as Parquet, atomically."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.Table.from_pylist(rows, schema=schema())
    with atomic_write(path, "wb") as handle:
        pq.write_table(table, handle)


def read_catalogue(path: str | os.PathLike) -> pa.Table:
    """The catalogue as a pyarrow Table."""
    import pyarrow.parquet as pq

    return pq.read_table(path)
