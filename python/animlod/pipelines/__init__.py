"""Pipelines: input files and options in, output files and a result record out.

The command line, ``make demo`` and the batch runner call these; they hold no argument parsing
and no printing.
"""

from .lod_document import DocumentReport, simplify_document

__all__ = ["DocumentReport", "simplify_document"]
