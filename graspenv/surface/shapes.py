"""Contact shapes: the rigid 2-D footprints that fingers, palms and objects press onto
the table, with their exact motion.

Every shape is a :class:`ContactShape` (graspenv/surface/contact_shape.py: the pose,
the twist and the exact motion law). The shapes, each in its own module:

- :class:`Fingertip` and :class:`Thumb`, ellipses that grow with the press
  (graspenv/surface/fingertip.py);
- :class:`Palm` and :class:`HandEdge`, rounded rectangles
  (graspenv/surface/rounded_box.py);
- :class:`PolygonShape`, any simple polygon (graspenv/surface/polygon.py).

Import them from here or from :mod:`graspenv.surface`.
"""

from __future__ import annotations

from graspenv.surface.contact_shape import ContactShape
from graspenv.surface.fingertip import Fingertip, Thumb
from graspenv.surface.polygon import PolygonShape
from graspenv.surface.rounded_box import HandEdge, Palm

__all__ = [
    "ContactShape",
    "Fingertip",
    "HandEdge",
    "Palm",
    "PolygonShape",
    "Thumb",
]
