"""Fuzz harness: read_gltf on any bytes named .gltf (JSON with data-URI buffers)."""

from reader_check import read_as

from animlod.io.gltf import read_gltf


def check(data: bytes) -> None:
    read_as(data, ".gltf", read_gltf)
