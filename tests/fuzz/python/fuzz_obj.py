"""Fuzz harness: an OBJ frame through read_sequence (what the CLI reads for a .obj)."""

from reader_check import read_as

from animlod.io.meshseq import read_sequence


def check(data: bytes) -> None:
    read_as(data, ".obj", read_sequence)
