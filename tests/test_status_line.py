"""Progress lines: rewritten in place on a terminal, a few plain lines in a log (roughness.core.status_line)."""
from __future__ import annotations

from roughness.core import status_line
from roughness.core.status_line import StatusLine


def test_a_log_gets_plain_lines_now_and_then_and_the_last_one(capsys, monkeypatch):
    line = StatusLine()  # stderr is captured here: not a terminal
    assert not line.terminal
    for i in range(400):
        line.show(f"reading {i + 1}/400", last=i == 399)
    line.close()
    assert capsys.readouterr().err == "reading 400/400\n"  # 400 updates within 30 s: only the last
    monkeypatch.setattr(status_line, "PLAIN_PROGRESS_SECONDS", 0.0)
    for i in range(3):
        line.show(f"  step {i}")
    assert capsys.readouterr().err == "step 0\nstep 1\nstep 2\n"


def test_a_terminal_gets_one_rewritten_line_ended_once(capsys):
    line = StatusLine()
    line.terminal = True
    line.show("1/2")
    line.show("2/2", last=True)
    line.close()
    line.close()
    assert capsys.readouterr().err == "\r1/2\r2/2\n"
