"""Offscreen video of a logged run (MuJoCo ``Renderer``; needs an EGL or OSMesa GL context).

The scene is rebuilt exactly as in the run (same robot, same scenario parameters, same seed, so the
same terrain) and the logged ``qpos`` is replayed at the video frame rate through the tracking
camera. Frames are written as MP4 when ``ffmpeg`` is on the PATH, otherwise use a ``.gif`` path
(Pillow, installed with matplotlib).

Offscreen rendering on a headless machine: set ``MUJOCO_GL=egl`` (or ``osmesa``) before MuJoCo is
imported; ``wbmpc walk --render FILE`` does it for you.
"""

from __future__ import annotations

import os
import shutil

import numpy as np

from wbmpc.errors import ParameterError


def render_run(log, path: str | os.PathLike, fps: int = 30, width: int = 640, height: int = 360) -> str:
    """Render ``log`` (a :class:`sim.log.RunLog`) into a video at ``path`` (.mp4 or .gif); returns the path."""
    import mujoco

    from robots import load_robot
    from robots.mujoco_model import build_mujoco_spec
    from sim.scenarios import make_scenario

    path = os.fspath(path)
    extension = os.path.splitext(path)[1].lower()
    if extension not in (".mp4", ".gif"):
        raise ParameterError(f"render path {path!r} must end with .mp4 or .gif")
    if extension == ".mp4" and shutil.which("ffmpeg") is None:
        raise ParameterError(f"render path {path!r}: MP4 needs ffmpeg on the PATH; use a .gif path instead")
    if not (isinstance(fps, int) and 1 <= fps <= 120):
        raise ParameterError(f"fps={fps!r} must be an integer in [1, 120]")

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
    directory = os.path.dirname(path)
    if directory:
        os.makedirs(directory, exist_ok=True)
    _write_video(frames, path, fps)
    return path


def _write_video(frames: list[np.ndarray], path: str, fps: int) -> None:
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from matplotlib import animation

    height, width = frames[0].shape[:2]
    fig = plt.figure(figsize=(width / 100, height / 100), dpi=100)
    ax = fig.add_axes([0, 0, 1, 1])
    ax.axis("off")
    image = ax.imshow(frames[0])
    writer = animation.FFMpegWriter(fps=fps) if path.endswith(".mp4") else animation.PillowWriter(fps=fps)
    with writer.saving(fig, path, dpi=100):
        for frame in frames:
            image.set_data(frame)
            writer.grab_frame()
    plt.close(fig)
