"""Warp candidates: the zones of an object that are not slabs across an axis, found together.

:func:`warp_candidates` gathers what :func:`~partscale.zones.find_radial` (a round or polygonal
plan and its annuli of constant radial section), :func:`~partscale.zones.find_screws` (a
flight's diagonal step), where no flight is found :func:`~partscale.zones.find_helices` (a
spiral stair's step) and, where neither is, :func:`~partscale.zones.find_rotations` (elements
repeated by a turn about the vertical: a star base's arms) find, each with the recipe edit that
uses it, as ``partscale suggest --json`` lists them. The web editor shows them and previews
their edits.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ..csdf import CSDF
from ..edit import screw_ground
from .helix import Helix, find_helices
from .radial import RadialFrame, find_radial, radial_zones
from .rotation import Rotation, find_rotations
from .screw import Screw, find_screws


@dataclass(frozen=True)
class WarpCandidates:
    """The warp zones found in one object (:func:`warp_candidates`).

    Parameters
    ----------
    radial : RadialFrame or None
        A round or regular-polygon outline in plan (about y).
    annuli : list of (float, float)
        Its annuli of constant radial section, ``(r0, r1)``, longest first (what a radial zone
        grows without deforming the rest).
    steps : list of Screw
        Flights repeating by a diagonal shift.
    helices : list of Helix
        Spiral stairs (looked for where no flight is found).
    grounds : list of float or None
        Per flight: the floor it stands on beyond its cut (:func:`~partscale.edit.screw_ground`).
    rotations : list of Rotation
        Rings or arcs of elements about the vertical (looked for where no stair is found).

    Examples
    --------
    >>> from partscale import shapes, zones
    >>> ball = shapes.sphere((0, 0, 0), 0.5, voxel_size=0.05)
    >>> found = zones.warp_candidates(ball)
    >>> found.radial.sides, found.steps, found.helices, found.rotations
    (0, [], [], [])
    """

    radial: RadialFrame | None = None
    annuli: list[tuple[float, float]] = field(default_factory=list)
    steps: list[Screw] = field(default_factory=list)
    helices: list[Helix] = field(default_factory=list)
    grounds: list[float | None] = field(default_factory=list)
    rotations: list[Rotation] = field(default_factory=list)

    def to_json(self) -> dict[str, Any]:
        """The JSON form: ``radial`` (the frame, its ``annuli`` and the ``edit`` of the longest
        annulus, unchanged; or None), ``steps``, ``helix`` and ``rotation`` (each as
        :meth:`Screw.to_json` / :meth:`Helix.to_json` / :meth:`Rotation.to_json`, with the
        ``edit`` adding one step or element, and for a flight its ``ground``): every ``edit`` is
        a recipe edit as recipes hold it.
        """
        radial = None
        if self.radial is not None:
            f = self.radial
            radial = {
                "axis": f.axis,
                "center": list(f.center),
                "sides": f.sides,
                "phase": f.phase,
                "radius": f.radius,
                "annuli": [list(a) for a in self.annuli],
            }
            if self.annuli:
                r0, r1 = self.annuli[0]
                radial["edit"] = f.zone(r0, r1, r1).to_json()
        steps = [
            {**sc.to_json(), "ground": g, "edit": sc.zone(1).to_json()}
            for sc, g in zip(self.steps, self.grounds, strict=True)
        ]
        helices = [{**hx.to_json(), "edit": hx.zone(1).to_json()} for hx in self.helices]
        turns = [{**rt.to_json(), "edit": rt.zone(1).to_json()} for rt in self.rotations]
        return {"radial": radial, "steps": steps, "helix": helices, "rotation": turns}


def warp_candidates(csdf: CSDF) -> WarpCandidates:
    """The radial frame, flights, spiral stairs and rings of elements of ``csdf`` (see module).

    Parameters
    ----------
    csdf : CSDF
        The object.

    Returns
    -------
    WarpCandidates
        Empty where none is found.

    Examples
    --------
    >>> import numpy as np
    >>> from partscale import shapes, zones
    >>> steps = [((0.2 * i, 0, 0), (0.2 * (i + 1), 0.15 * (i + 1), 0.8)) for i in range(6)]
    >>> flight = shapes.grid(lambda p: shapes.boxes_sdf(p, steps), [(0, 0, 0), (1.2, 0.9, 0.8)], voxel_size=0.02)
    >>> found = zones.warp_candidates(flight)
    >>> found.to_json()["steps"][0]["edit"]["copies"]
    1
    """
    frame = find_radial(csdf, "y")
    annuli = radial_zones(csdf, frame) if frame is not None else []
    steps = find_screws(csdf)
    helices = find_helices(csdf) if not steps else []
    rotations = find_rotations(csdf) if not steps and not helices else []
    grounds = [screw_ground(csdf, sc.zone(1)) for sc in steps]
    return WarpCandidates(frame, annuli, steps, helices, grounds, rotations)
