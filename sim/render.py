"""Videos of runs: an offscreen video of a logged run, and MuJoCo's viewer live during a run.

:func:`render_run` rebuilds the scene exactly as in the run (same robot, same scenario parameters,
same seed, so the same terrain) and replays the logged ``qpos`` at the video frame rate through the
tracking camera (MuJoCo ``Renderer``; needs an EGL or OSMesa GL context). MP4 is encoded by the
ffmpeg that the ``imageio-ffmpeg`` wheel ships (no system ffmpeg needed); GIF by Pillow.

Offscreen rendering on a headless machine: set ``MUJOCO_GL=egl`` (or ``osmesa``) before MuJoCo is
imported; ``wbmpc walk --render FILE`` does it for you.

:class:`LiveViewer` is an ``on_tick(model, data)`` observer for :func:`sim.run_scenario`: it opens
``mujoco.viewer.launch_passive`` at the first tick and syncs it every few ticks.
"""

from __future__ import annotations

import os
import sys

import numpy as np

from wbmpc.errors import ParameterError

VIDEO_EXTENSIONS = (".mp4", ".gif")


def check_video_path(path: str | os.PathLike) -> str:
    """Return the extension of a video path (".mp4" or ".gif").

    Raises:
        ParameterError: another extension, or an existing directory.
    """
    path = os.fspath(path)
    extension = os.path.splitext(path)[1].lower()
    if extension not in VIDEO_EXTENSIONS:
        raise ParameterError(f"render path {path!r} must end with .mp4 or .gif")
    if os.path.isdir(path):
        raise ParameterError(f"render path {path!r} is a directory; give a file path")
    return extension


def render_run(log, path: str | os.PathLike, fps: int = 30, width: int = 640, height: int = 360) -> str:
    """Render ``log`` (a :class:`sim.log.RunLog`) into a video at ``path`` (.mp4 or .gif); returns the path.

    Args:
        fps: frames per second of the video, an integer in [1, 120].
        width, height: frame size [pixels], even numbers (the MP4 encoder's YUV 4:2:0 needs it).
    """
    import mujoco

    from robots import load_robot
    from robots.mujoco_model import build_mujoco_spec
    from sim.scenarios import make_scenario

    path = os.fspath(path)
    check_video_path(path)
    if not (isinstance(fps, int) and 1 <= fps <= 120):
        raise ParameterError(f"fps={fps!r} must be an integer in [1, 120]")
    for name, value in (("width", width), ("height", height)):
        if not (isinstance(value, int) and value >= 16 and value % 2 == 0):
            raise ParameterError(f"{name}={value!r} pixels must be an even integer >= 16")

    robot = load_robot(log.robot)
    spec = build_mujoco_spec(robot, link_collisions=True)
    scenario = make_scenario(log.scenario, **log.params["scenario"])
    scenario.modify_spec(spec, np.random.default_rng(log.seed))
    model = spec.compile()
    data = mujoco.MjData(model)
    try:
        renderer = mujoco.Renderer(model, height, width)
    except Exception as err:  # no GL context on this machine
        raise ParameterError(
            f"offscreen rendering is not available ({type(err).__name__}: {err}); set MUJOCO_GL=egl or osmesa"
        ) from err
    camera = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, "track")
    t, qpos = log.ticks["t"], log.ticks["qpos"]
    if len(t) == 0:
        raise ParameterError("the log has no ticks to render")
    frames = []
    for time_s in np.arange(t[0], t[-1] + 1e-9, 1.0 / fps):
        data.qpos[:] = qpos[min(int(np.searchsorted(t, time_s)), len(t) - 1)]
        mujoco.mj_forward(model, data)
        renderer.update_scene(data, camera=camera if camera >= 0 else -1)
        frames.append(renderer.render().copy())
    renderer.close()
    write_video(frames, path, fps)
    return path


def write_video(frames: list[np.ndarray], path: str | os.PathLike, fps: int) -> str:
    """Write RGB frames (each (height, width, 3) uint8) to ``path``: H.264 MP4 or GIF; returns the path."""
    path = os.fspath(path)
    extension = check_video_path(path)
    if not frames:
        raise ParameterError("no frames to write")
    directory = os.path.dirname(path)
    if directory:
        os.makedirs(directory, exist_ok=True)
    height, width = frames[0].shape[:2]
    if extension == ".mp4":
        import imageio_ffmpeg  # ships its own ffmpeg binary

        writer = imageio_ffmpeg.write_frames(path, (width, height), fps=fps, macro_block_size=2,
                                             ffmpeg_log_level="error")
        writer.send(None)  # start the encoder
        for frame in frames:
            writer.send(np.ascontiguousarray(frame, dtype=np.uint8))
        writer.close()
        return path
    from PIL import Image

    images = [Image.fromarray(np.asarray(frame, dtype=np.uint8)) for frame in frames]
    images[0].save(path, save_all=True, append_images=images[1:], duration=round(1000 / fps), loop=0)
    return path


def viewer_unavailable() -> str | None:
    """Why MuJoCo's interactive viewer cannot open here (None: it can try)."""
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        return "no display (neither DISPLAY nor WAYLAND_DISPLAY is set); use --render FILE.mp4 for a video instead"
    try:
        import mujoco.viewer  # noqa: F401  (imports GLFW)
    except Exception as err:
        return f"MuJoCo's viewer cannot be imported ({type(err).__name__}: {err})"
    return None


class LiveViewer:
    """``on_tick(model, data)`` observer: MuJoCo's passive viewer, synced every ``sync_every`` ticks.

    The window opens at the first tick (the model exists only then); closing it leaves the run going.

    Args:
        sync_every: ticks between two syncs (16 ticks of 1 ms: ~60 frames per simulated second).

    Raises (from the first call):
        ParameterError: the viewer did not start (no display, no GL).
    """

    def __init__(self, sync_every: int = 16) -> None:
        if not (isinstance(sync_every, int) and sync_every >= 1):
            raise ParameterError(f"sync_every={sync_every!r} must be an integer >= 1")
        self.sync_every = sync_every
        self.handle = None
        self.ticks = 0

    def __call__(self, model, data) -> None:
        if self.handle is None:
            import mujoco.viewer

            try:
                self.handle = mujoco.viewer.launch_passive(model, data)
            except Exception as err:
                raise ParameterError(f"--viewer: MuJoCo's viewer did not start ({type(err).__name__}: {err})") from err
        if self.ticks % self.sync_every == 0 and self.handle.is_running():
            self.handle.sync()
        self.ticks += 1

    def close(self) -> None:
        """Close the window (if it opened)."""
        if self.handle is not None:
            self.handle.close()
            self.handle = None
