"""``graspenv serve`` as a user runs it: it prints its URL, answers, and stops
cleanly on Ctrl-C; bad arguments are one-line errors."""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
import time
import urllib.request

import pytest

from graspenv.cli import main


def test_serve_prints_its_url_answers_and_stops_on_ctrl_c() -> None:
    process = subprocess.Popen(
        [sys.executable, "-m", "graspenv.cli", "serve", "--port", "0", "--tuio", "0"],
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert process.stderr is not None
        url = None
        deadline = time.monotonic() + 120
        while url is None and time.monotonic() < deadline:
            line = process.stderr.readline()
            if not line:
                break
            found = re.search(r"(http://127\.0\.0\.1:\d+/)", line)
            url = found.group(1) if found else None
        assert url, "no URL printed"
        with urllib.request.urlopen(url + "state", timeout=10) as reply:
            state = json.load(reply)
        assert "box" in state["objects"]
        process.send_signal(signal.SIGINT)
        _, rest = process.communicate(timeout=30)
        assert process.returncode == 0
        assert "stopped" in rest and "Traceback" not in rest
    finally:
        if process.poll() is None:
            process.kill()
            process.wait(timeout=10)


@pytest.mark.parametrize(
    "argv, words",
    [
        (["serve", "--port", "70000"], "--port must be a port number"),
        (["serve", "--env", "graspenv/Nothing-v0"], "unknown environment"),
        (["serve", "--config", "no/such/scene.toml"], "no/such/scene.toml"),
    ],
)
def test_bad_arguments_are_one_line_errors(
    argv: list[str], words: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err
