"""Live touch: a person's fingers on a browser page, or a tabletop tracker speaking
TUIO, drive the table in real time (``graspenv serve``).

Every input becomes a contact mask at the camera's resolution and goes through the
whole pipeline (contours, persistent proxies, PyBullet), exactly as a synthetic
hand's mask does:

- :mod:`graspenv.live.touches`: touches as ellipses on the table, validated and
  bounded, and the board that merges every source of them;
- :mod:`graspenv.live.tuio`: TUIO 1.1 (``/tuio/2Dcur``, ``/tuio/2Dblb``) over UDP;
- :mod:`graspenv.live.table`: the table's 60 Hz loop, which drops frames rather
  than queue them when the machine falls behind;
- :mod:`graspenv.live.server`: the web server (aiohttp): the page, ``GET /state``,
  ``POST /reset`` and the page's WebSocket.

Needs the ``serve`` extra (``pip install 'graspenv[serve]'``).
"""
