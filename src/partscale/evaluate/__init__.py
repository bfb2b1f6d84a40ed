"""Measured evaluation: an edit against its original, and the suite of real objects.

- :mod:`.metrics`: one edit result against the original (length, rigidity, proportions, spacing,
  distances, topology, seams).
- :mod:`.suite`: every suite object in every mode, with figures and tables (``partscale eval``).
"""

from .metrics import EditGeometry, Reference, evaluate, resolve_edit
from .suite import MODES, Suite, SuiteResult, load_suite, run_suite

__all__ = [
    "MODES",
    "EditGeometry",
    "Reference",
    "Suite",
    "SuiteResult",
    "evaluate",
    "load_suite",
    "resolve_edit",
    "run_suite",
]
