"""Measured evaluation: an edit against its original, and the suite of real objects.

- :mod:`.metrics`: one edit result against the original (length, rigidity, proportions, spacing,
  distances, topology, seams).
- :mod:`.compare`: an edited file (or a recipe) against its original, zones from its history
  (``partscale eval --original A --edited B``).
- :mod:`.suite`: every suite object in every mode, with figures and tables (``partscale eval``).
"""

from .compare import score_edit
from .metrics import Reference, Zone, Zones, evaluate, zones_from_history
from .report import CRITERIA
from .suite import COMPARED_MODES, RECIPE_MODES, Suite, SuiteResult, load_suite, run_suite

__all__ = [
    "COMPARED_MODES",
    "CRITERIA",
    "RECIPE_MODES",
    "Reference",
    "Suite",
    "SuiteResult",
    "Zone",
    "Zones",
    "evaluate",
    "load_suite",
    "run_suite",
    "score_edit",
    "zones_from_history",
]
