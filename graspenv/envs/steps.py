"""Episode lengths, kept apart so registration imports nothing heavy."""

from __future__ import annotations

#: Task name → episode length in environment steps (``task.frame_skip`` camera
#: frames each, 30 steps per second by default).
EPISODE_STEPS: dict[str, int] = {
    "SqueezeHold": 70,
    "TurnInPlace": 150,
    "SqueezeSlide": 150,
    "SidePush": 150,
    "TopRub": 150,
    "CatchBall": 120,
}
