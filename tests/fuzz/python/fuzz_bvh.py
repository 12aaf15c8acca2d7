"""Fuzz harness: read_bvh on any bytes."""

from reader_check import read_as

from animlod.io.bvh import read_bvh


def check(data: bytes) -> None:
    read_as(data, ".bvh", read_bvh)
