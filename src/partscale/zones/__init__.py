"""Zones that find themselves: suggested zones, snapping and fit-to-size (between segment and edit)."""

from .profile import Profile, profile
from .suggest import Candidate, axis_candidates, suggest

__all__ = ["Candidate", "Profile", "axis_candidates", "profile", "suggest"]
