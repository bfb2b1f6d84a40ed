"""One edit result measured against its original: an edited file, or a recipe applied here.

The metrics are :func:`partscale.evaluate.metrics.evaluate`'s; the zones come from the edited
object's history (every scale edit since the original: several edits, several zones).
"""

from __future__ import annotations

from typing import Any

from ..csdf import CSDF
from ..edit import Recipe, apply_recipe
from ..errors import InputError
from . import metrics


def score_edit(
    original: CSDF, edited: CSDF | None = None, *, recipe: Recipe | dict | None = None
) -> dict[str, Any]:
    """The metrics of ``edited`` (or of ``recipe`` applied to ``original``) against ``original``.

    Parameters
    ----------
    original : CSDF
        The object before the edit.
    edited : CSDF, optional
        An edit result of ``original``: its history holds ``original``'s entries followed by
        one or more scale edits (each a zone), e.g. a file written by ``partscale scale``.
    recipe : Recipe or its JSON, optional
        Applied to ``original`` with :func:`partscale.edit.apply_recipe`, then scored. Exactly
        one of ``edited`` and ``recipe``.

    Returns
    -------
    dict
        ``metrics`` (name -> value, as in the suite's tables), ``reference`` (the original's
        own distance error and pieces in the same zones), ``zones`` (one per edit, in the
        original's frame: ``axis``, ``zone``, ``new_zone``, ``mode``, ``copies``) and
        ``failures`` (the short names of the metrics above the suite's thresholds).

    Examples
    --------
    A bar's middle stretched by the stage: the right length, the rest rigid, nothing failed.

    >>> from partscale import evaluate, shapes
    >>> bar = shapes.box((0, 0, 0), (1.0, 0.2, 0.2), voxel_size=0.05)
    >>> recipe = {"edits": [{"axis": "x", "zone": [0.3, 0.6], "to": 0.8}]}
    >>> scores = evaluate.score_edit(bar, recipe=recipe)
    >>> scores["zones"], scores["failures"]
    ([{'axis': 'x', 'zone': [0.3, 0.6], 'new_zone': [0.3, 0.8], 'mode': 'stretch'}], [])
    >>> float(scores["metrics"]["length_err"]) < 0.5, scores["metrics"]["rigid_err"] < 0.25
    (True, True)
    """
    if (edited is None) == (recipe is None):
        raise InputError(
            "expected an edited CSDF or a recipe (exactly one), got "
            + ("both" if edited is not None else "neither")
        )
    if recipe is not None:
        edited = apply_recipe(original, recipe)
    assert edited is not None
    hist_a = original.meta.get("history", [])
    hist_b = edited.meta.get("history", [])
    if hist_b[: len(hist_a)] != hist_a:
        raise InputError(
            "edited: expected a result of the original (its history starting with the "
            f"original's {len(hist_a)} entries), got a different history"
        )
    zones = metrics.zones_from_history(edited, original)
    ref = metrics.Reference(original)
    m = metrics.evaluate(ref, edited, zones)
    base = metrics.evaluate_original(ref, zones)
    from .report import failures_of

    return {
        "metrics": m,
        "reference": base,
        "zones": [
            {
                "axis": "xyz"[z.axis],
                "zone": [z.start, z.end],
                "new_zone": [z.new_start, z.new_end],
                "mode": z.mode,
                **({"copies": z.n_copies} if z.mode == "tile" else {}),
            }
            for z in zones.zones
        ],
        "failures": failures_of(m, base),
    }
