"""``graspenv bench --speed`` end to end on small budgets (its figures are speeds,
which no test asserts: only that every part runs and is reported)."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from graspenv.bench import speed


def test_speed_report_covers_every_part_and_writes_its_files(tmp_path: Path) -> None:
    lines: list[str] = []
    report = speed.run_speed(
        lines.append, runs=1, env_steps=5, envs=["graspenv/SidePush-v0"], with_compile=False,
        with_scaling=False,
    )  # fmt: skip
    report.scaling = speed.scaling(frames=2, counts=(1, 10, 100))
    assert [s.name for s in report.scenes] == [
        "turn, default",
        "turn, fast",
        "turn, coarse",
        "two hands, default",
    ]
    for scene in report.scenes:
        assert scene.frames > 100 and scene.realtime > 0 and 0 < scene.bullet_share < 1
        assert set(scene.stage_minima) == {"sensing", "matching", "control", "physics"}
    (env,) = report.envs
    assert env.strategy == "push-from-behind"  # from the graspenv.strategies entry points
    assert env.scripted > 0 and env.random > 0
    assert report.peer > 0  # panda-gym is in the dev extra
    assert set(report.reset_ms) == {"simulation, same scene", "environment, new object"}
    figures = [row[0] for row in report.targets()]
    assert "canonical turn, default fidelity" in figures
    assert "env steps/s vs panda-gym, random actions" in figures
    assert any(f.startswith("frame cost for 10× the contacts") for f in figures)
    written = report.write(tmp_path)
    assert {p.name for p in written} == {"speed.md", "speed.csv", "scaling.png"}
    assert "| canonical turn, default fidelity |" in (tmp_path / "speed.md").read_text()
    assert any(line.startswith("peer:") for line in lines)


def test_contact_masks_hold_the_contacts_asked_for() -> None:
    shape = (480, 640)
    for count in (1, 10, 100, 1000):
        (tips,) = speed.fingertip_masks(count, 1, shape)
        found, _ = cv2.findContours(tips, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
        assert len(found) == count
    speckles = speed.speckle_masks(50, 2, shape)
    assert not np.array_equal(speckles[0], speckles[1])  # drawn anew each frame
    assert np.count_nonzero(speckles[0]) <= 50 * speed.SPECKLE_PIXELS**2
