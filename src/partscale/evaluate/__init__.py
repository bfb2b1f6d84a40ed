"""Measured evaluation: an edit against its original, and the suite of real objects.

- :mod:`.metrics`: one edit result against the original (length, rigidity, proportions, spacing,
  distances, topology, seams).
- :mod:`.suite`: every suite object in every mode, with figures and tables (``partscale eval``).
"""

from .metrics import Reference, evaluate
from .suite import COMPARED_MODES, Suite, SuiteResult, load_suite, run_suite

__all__ = [
    "COMPARED_MODES",
    "Reference",
    "Suite",
    "SuiteResult",
    "evaluate",
    "load_suite",
    "run_suite",
]
