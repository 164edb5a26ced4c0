"""``kill -9`` of a campaign's parent process ends its pool workers within seconds (they do not run on)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

pytestmark = pytest.mark.skipif(not os.path.isdir("/proc"), reason="lists processes through /proc")


def session_processes(session: int) -> dict[int, str]:
    """Live (not zombie) processes of a session: pid -> command line."""
    found = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as stream:
                stat = stream.read()
            with open(f"/proc/{entry}/cmdline", "rb") as stream:
                command = stream.read().replace(b"\0", b" ").decode(errors="replace")
        except OSError:  # ended meanwhile
            continue
        fields = stat[stat.rindex(")") + 2:].split()  # after "pid (comm) ": state ppid pgrp session ...
        if fields[0] != "Z" and int(fields[3]) == session:
            found[int(entry)] = command
    return found


def test_workers_end_when_the_campaign_parent_is_killed(tmp_path):
    argv = [
        sys.executable, "-m", "wbmpc.cli", "campaign", "push-map", "--controller", "pd", "--steps-x", "3",
        "--steps-y", "3", "--phases", "0", "0.5", "--push-after", "0.2", "--duration", "2.0", "--set",
        "stop_on_fall=False", "--out", str(tmp_path / "killed"), "--no-progress", "--no-plots", "--workers", "2",
    ]
    process = subprocess.Popen(argv, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 60.0
        while len(session_processes(process.pid)) < 4:  # campaign, forkserver, 2 workers (and a resource tracker)
            if process.poll() is not None:
                pytest.fail(f"campaign ended early: {process.stderr.read().decode()[-2000:]}")
            if time.monotonic() > deadline:
                pytest.fail(f"the pool did not start within 60 s: {session_processes(process.pid)}")
            time.sleep(0.05)
        time.sleep(0.5)  # trials running
        os.kill(process.pid, signal.SIGKILL)  # the parent only
        process.wait()
        killed_at = time.monotonic()
        while session_processes(process.pid):
            if time.monotonic() - killed_at > 5.0:
                pytest.fail(f"processes still running 5 s after the kill: {session_processes(process.pid)}")
            time.sleep(0.05)
        print(f"all workers ended {time.monotonic() - killed_at:.2f} s after the kill")
    finally:
        try:
            os.killpg(process.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
