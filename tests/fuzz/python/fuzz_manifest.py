"""Fuzz harness: read_lod_manifest on any bytes."""

from reader_check import read_as

from animlod.io.manifest import read_lod_manifest


def check(data: bytes) -> None:
    read_as(data, ".json", read_lod_manifest)
