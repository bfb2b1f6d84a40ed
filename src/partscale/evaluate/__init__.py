"""Measured evaluation: an edit against its original, and the suite of real objects.

- :mod:`.metrics`: one edit result against the original (length, rigidity, proportions, spacing,
  distances, topology, seams).
- :mod:`.compare`: an edited file (or a recipe) against its original, zones from its history
  (``partscale eval --original A --edited B``).
- :mod:`.suite`: every suite object in every mode, with figures and tables (``partscale eval``).
- :mod:`.virtual` and :mod:`.completion`: virtual scans of complete objects as a Kinect-like
  sensor sees them (:func:`virtual_scan`), and a completion scored against the complete object
  (:func:`chamfer_fscore`, :func:`f_tau`, :func:`surface_samples`, :func:`colour_error`,
  :data:`F_TAU`).
- :func:`metric_score`, :func:`failures_of`, :func:`winners`: how the suite's report scores a
  result on one metric, lists its failures (:data:`CRITERIA` thresholds) and picks the best modes.
"""

from .compare import score_edit
from .completion import (
    F_TAU,
    chamfer_fscore,
    colour_error,
    exterior,
    f_tau,
    surface_samples,
)
from .metrics import Reference, Zone, Zones, evaluate, zones_from_history
from .report import CRITERIA, failures_of, metric_score, winners
from .suite import COMPARED_MODES, RECIPE_MODES, Suite, SuiteResult, load_suite, run_suite
from .virtual import virtual_scan

__all__ = [
    "COMPARED_MODES",
    "CRITERIA",
    "F_TAU",
    "RECIPE_MODES",
    "Reference",
    "Suite",
    "SuiteResult",
    "Zone",
    "Zones",
    "chamfer_fscore",
    "colour_error",
    "evaluate",
    "exterior",
    "f_tau",
    "failures_of",
    "load_suite",
    "metric_score",
    "run_suite",
    "score_edit",
    "surface_samples",
    "virtual_scan",
    "winners",
    "zones_from_history",
]
