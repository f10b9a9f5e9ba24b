"""The `graspenv` command: what it writes, and one-line errors for bad input."""

from __future__ import annotations

from pathlib import Path

import cv2
import pytest

from graspenv.cli import main


def test_demo_writes_picture_animation_and_numbers(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["demo", "--out", str(tmp_path)]) == 0
    printed = capsys.readouterr().out
    assert "turn:" in printed and "slide:" in printed
    picture = cv2.imread(str(tmp_path / "demo.png"))
    assert picture is not None and picture.shape[0] > 100
    assert (tmp_path / "demo.gif").stat().st_size > 1000
    summary = (tmp_path / "demo.txt").read_text()
    # The demo's own figures: the box follows the fingers' 90° turn and 10 cm slide.
    error = float(summary.split("error")[1].split("°")[0])
    ratio = float(summary.split("ratio")[1])
    assert abs(error) <= 1.0
    assert abs(ratio - 1.0) <= 0.02


def test_interactions_writes_a_table(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "table.md"
    args = ["interactions", "--scenario", "side strike", "--method", "persistent"]
    assert main([*args, "--out", str(out)]) == 0
    table = out.read_text()
    assert table.startswith("| interaction | figure |")
    assert "| side strike | along_mm |" in table
    assert "[1/1] side strike / persistent" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["interactions", "--method", "magic"], "unknown method 'magic'"),
        (["interactions", "--scenario", "juggle"], "unknown scenario 'juggle'"),
        (["demo", "--config", "missing.toml"], "missing.toml"),
        (["replay", "no/such/folder"], "no/such/folder"),
        (["bench", "--sample", "5"], "--sample N goes with --grid"),
        (["bench", "--grid", "--sample", "0"], "N at least 1"),
    ],
)
def test_bad_arguments_end_with_one_line(
    argv: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert message in err
    assert len(err.splitlines()) == 1
    assert "Traceback" not in err


def test_bad_config_value_names_the_key(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "bad.toml"
    path.write_text("[proxy]\nwindow = -1\n")
    assert main(["demo", "--config", str(path), "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "proxy.window" in err and str(path) in err
