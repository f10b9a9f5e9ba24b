"""The live table's latency and frame time: ``python -m graspenv.bench.live_latency``.

A page's WebSocket on loopback puts a fingertip down on an empty part of the
default table and lifts it again, ``--cycles`` times; each time it polls
``GET /state`` (every millisecond) until the state reflects the change (a contact
appears, then none). The latency is the wall time from sending the touch to the
first state that reflects it: the WebSocket, the wait for the table's next frame
(up to 1/60 s), the frame's work, and one HTTP round trip. The table's own frame
time (mask, pipeline) is then read while a pinch squeezes the box, and its dropped
frames over the whole run.

Prints a Markdown table; needs the ``serve`` extra.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import statistics
import time

import aiohttp
import numpy as np

from graspenv.config import load_config
from graspenv.live.server import serving_in_thread
from graspenv.live.table import LiveTable


async def _measure(url: str, cycles: int) -> tuple[list[float], list[float]]:
    downs: list[float] = []
    ups: list[float] = []
    async with (
        aiohttp.ClientSession() as session,
        session.ws_connect(url.replace("http://", "ws://") + "ws") as ws,
    ):

        async def contacts() -> int:
            async with session.get(url + "state") as reply:
                return int((await reply.json())["contacts"])

        for k in range(cycles):
            for touching, out in ((True, downs), (False, ups)):
                # Alternate positions, away from the box at the centre.
                x = 0.15 + 0.1 * (k % 3)
                touches = [{"x": x, "y": 0.2}] if touching else []
                sent = time.perf_counter()
                await ws.send_str(json.dumps({"type": "touches", "touches": touches}))
                deadline = sent + 2.0
                while time.perf_counter() < deadline:
                    if (await contacts() > 0) == touching:
                        out.append(time.perf_counter() - sent)
                        break
                    await asyncio.sleep(0.001)
                await asyncio.sleep(0.05)
        # Then a pinch squeezing the box, held for a second and a bit: the frame time
        # of a grasp (two contacts, their particles against the box).
        for reach in np.linspace(0.040, 0.035, 20):  # down beside it, then squeeze
            pinch = [{"x": 0.5 + side * reach / 0.61, "y": 0.5} for side in (-1, 1)]
            await ws.send_str(json.dumps({"type": "touches", "touches": pinch}))
            await asyncio.sleep(1 / 60)
        await asyncio.sleep(1.2)
    return downs, ups


def _row(name: str, values: list[float]) -> str:
    ms = sorted(1000.0 * v for v in values)
    p95 = ms[min(len(ms) - 1, round(0.95 * (len(ms) - 1)))]
    return f"| {name} | {len(ms)} | {statistics.median(ms):.1f} | {p95:.1f} | {ms[-1]:.1f} |"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cycles", type=int, default=50, help="touch-downs and lifts")
    args = parser.parse_args()
    table = LiveTable(load_config(None))
    with serving_in_thread(table) as server:
        downs, ups = asyncio.run(_measure(server.url, args.cycles))
        state = table.state()
    print("| touch to state | n | median ms | 95th percentile ms | max ms |")
    print("|---|---|---|---|---|")
    print(_row("touch-down (a contact appears)", downs))
    print(_row("lift (it goes)", ups))
    print()
    print(
        f"table, over the last second (a pinch squeezing the box: {state.contacts} "
        f"contacts, {state.grip_force['box']:.1f} N): {state.fps:.1f} frames/s, mean "
        f"frame time {state.frame_ms:.2f} ms (mask and pipeline); "
        f"{state.dropped} frames dropped of {state.frame + state.dropped} in the run"
    )


if __name__ == "__main__":
    main()
