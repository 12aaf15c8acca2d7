"""Fuzz harness: read_gltf on any bytes named .glb (binary container, skins, animations)."""

from reader_check import read_as

from animlod.io.gltf import read_gltf


def check(data: bytes) -> None:
    read_as(data, ".glb", read_gltf)
