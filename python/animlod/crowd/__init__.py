"""The native crowd benchmark from Python: run ``animlod_crowd`` on LoD GLBs, read its report,
draw Fig. 1 as a heat map. The renderer is the C++ binary in bench/crowd/; nothing here draws."""

from .chains import character_chain, procedural_chain, procedural_source
from .figures import write_heat_map
from .runner import MODES, PATHS, CrowdError, CrowdReport, find_crowd_binary, mode_list, run_crowd

__all__ = [
    "MODES",
    "PATHS",
    "CrowdError",
    "CrowdReport",
    "character_chain",
    "find_crowd_binary",
    "mode_list",
    "procedural_chain",
    "procedural_source",
    "run_crowd",
    "write_heat_map",
]
