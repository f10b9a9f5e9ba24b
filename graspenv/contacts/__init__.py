"""Contacts: mask components, their outer contours, even resampling, frame-to-frame
tracking, and the persistent proxy's point correspondence (numpy, cv2 and compiled
kernels; no physics).

Typical use, one camera frame at a time::

    tracker = ContactTracker(surface, config.contacts)
    frame = tracker.update(mask)            # ContactFrame: new / continuing / removed
    for contact in frame.continuing:
        match = correspond(previous_points, contact.contour, window=4)
"""

from __future__ import annotations

from graspenv.contacts.cleanup import MaskCleaner
from graspenv.contacts.extract import Component, find_components, outline_from_chain, validate_mask
from graspenv.contacts.matching import (
    Correspondence,
    agreement,
    correspond,
    correspond_batch,
    match_exhaustive,
    match_fast,
    new_point_anchors,
    window_costs,
)
from graspenv.contacts.resample import orient_ccw, resample_closed, signed_area
from graspenv.contacts.tracking import Contact, ContactFrame, ContactStatus, ContactTracker

__all__ = [
    "Component",
    "Contact",
    "ContactFrame",
    "ContactStatus",
    "ContactTracker",
    "Correspondence",
    "MaskCleaner",
    "agreement",
    "correspond",
    "correspond_batch",
    "find_components",
    "match_exhaustive",
    "match_fast",
    "new_point_anchors",
    "orient_ccw",
    "outline_from_chain",
    "resample_closed",
    "signed_area",
    "validate_mask",
    "window_costs",
]
