"""Videos: MP4 through the ffmpeg of the imageio-ffmpeg wheel (no system ffmpeg), GIF, and the live viewer's checks."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from sim.render import LiveViewer, check_video_path, write_video
from wbmpc.errors import ParameterError


def read_video(path):
    """(frames, width, height) of a video decoded by imageio-ffmpeg's ffmpeg."""
    import imageio_ffmpeg

    reader = imageio_ffmpeg.read_frames(str(path))
    meta = next(reader)
    frames = list(reader)
    return frames, *meta["size"]


def test_mp4_is_written_without_a_system_ffmpeg(tmp_path, monkeypatch):
    monkeypatch.setenv("PATH", "")  # no ffmpeg on the PATH: the wheel's binary is used
    rng = np.random.default_rng(0)
    frames = [np.full((48, 64, 3), 10 * k, dtype=np.uint8) + rng.integers(0, 5, (48, 64, 3), dtype=np.uint8)
              for k in range(12)]
    path = write_video(frames, tmp_path / "clip" / "run.mp4", fps=12)
    with open(path, "rb") as stream:
        assert stream.read(12)[4:8] == b"ftyp"  # an ISO base media (MP4) file
    decoded, width, height = read_video(path)
    assert (width, height) == (64, 48) and len(decoded) == 12


def test_gif_and_bad_paths(tmp_path):
    frames = [np.zeros((16, 16, 3), np.uint8), np.full((16, 16, 3), 255, np.uint8)]
    gif = write_video(frames, tmp_path / "run.gif", fps=5)
    assert open(gif, "rb").read(6) == b"GIF89a"
    with pytest.raises(ParameterError, match=r"render path 'run.avi' must end with .mp4 or .gif"):
        check_video_path("run.avi")
    (tmp_path / "dir.mp4").mkdir()
    with pytest.raises(ParameterError, match="is a directory"):
        check_video_path(tmp_path / "dir.mp4")


def test_render_run_writes_a_valid_mp4_of_a_short_run(tmp_path):
    code = ("import mujoco; m = mujoco.MjModel.from_xml_string('<mujoco/>'); mujoco.Renderer(m, 16, 16)")
    probe = subprocess.run([sys.executable, "-c", code], env={**os.environ, "MUJOCO_GL": "egl"}, capture_output=True)
    if probe.returncode != 0:
        pytest.skip("no EGL context for offscreen rendering on this machine")
    video = tmp_path / "walk.mp4"
    script = ("import sys; from wbmpc.cli import main; "
              f"sys.exit(main(['walk', '--controller', 'pd', '--duration', '0.3', '--render', {str(video)!r}]))")
    headless = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "DISPLAY", "WAYLAND_DISPLAY")}
    run = subprocess.run([sys.executable, "-c", script], env=headless,  # the CLI chooses EGL itself
                         capture_output=True, text=True, cwd=os.getcwd())
    assert run.returncode in (0, 1), run.stderr[-2000:]  # 1: the PD controller may fall
    frames, width, height = read_video(video)
    assert (width, height) == (640, 360) and len(frames) >= 9  # 30 fps over 0.3 s


def test_viewer_without_a_display_is_one_line_before_the_run(capsys, monkeypatch, tmp_path):
    from wbmpc.cli import main

    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr(sys, "platform", "linux")
    assert main(["walk", "--viewer", "--out", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err
    assert err == ("wbmpc walk: error: --viewer: no display (neither DISPLAY nor WAYLAND_DISPLAY is set); "
                   "use --render FILE.mp4 for a video instead\n")
    assert not (tmp_path / "run").exists()  # refused before the run


class FakeHandle:
    def __init__(self):
        self.syncs, self.closed = 0, False

    def is_running(self):
        return True

    def sync(self):
        self.syncs += 1

    def close(self):
        self.closed = True


def test_live_viewer_opens_at_the_first_tick_and_syncs_every_few_ticks(monkeypatch):
    import mujoco.viewer

    from sim import run_scenario

    handles = []
    monkeypatch.setattr(mujoco.viewer, "launch_passive", lambda model, data: handles.append(FakeHandle()) or handles[-1])
    viewer = LiveViewer(sync_every=10)
    run_scenario("walk", controller="pd", duration=0.1, on_tick=viewer, progress=False)
    viewer.close()
    assert len(handles) == 1 and handles[0].syncs == 10 and handles[0].closed


def test_live_viewer_that_cannot_start_is_a_parameter_error(monkeypatch):
    import mujoco.viewer

    def fail(model, data):
        raise RuntimeError("could not open a GLFW window")

    monkeypatch.setattr(mujoco.viewer, "launch_passive", fail)
    with pytest.raises(ParameterError, match=r"--viewer: MuJoCo's viewer did not start \(RuntimeError: could not"):
        LiveViewer()(None, None)
