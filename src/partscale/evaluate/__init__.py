"""Measured evaluation: an edit against its original, and the suite of real objects.

- :mod:`.metrics`: one edit result against the original (length, rigidity, proportions, spacing,
  distances, topology, seams).
- :mod:`.compare`: an edited file (or a recipe) against its original, zones from its history
  (``partscale eval --original A --edited B``).
- :mod:`.suite`: every suite object in every mode, with figures and tables (``partscale eval``).
"""

from .compare import score_edit
from .metrics import (
    EditGeometry,
    Reference,
    Zone,
    Zones,
    evaluate,
    resolve_edit,
    zones_from_history,
)
from .suite import MODES, Suite, SuiteResult, load_suite, run_suite

__all__ = [
    "MODES",
    "EditGeometry",
    "Reference",
    "Suite",
    "SuiteResult",
    "Zone",
    "Zones",
    "evaluate",
    "load_suite",
    "resolve_edit",
    "run_suite",
    "score_edit",
    "zones_from_history",
]
