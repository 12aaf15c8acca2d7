"""Fuzz harness: a PLY frame through read_sequence (ascii and binary bodies)."""

from reader_check import read_as

from animlod.io.meshseq import read_sequence


def check(data: bytes) -> None:
    read_as(data, ".ply", read_sequence)
