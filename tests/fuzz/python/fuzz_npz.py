"""Fuzz harness: read_npz on any bytes."""

from reader_check import read_as

from animlod.io.npz import read_npz


def check(data: bytes) -> None:
    read_as(data, ".npz", read_npz)
