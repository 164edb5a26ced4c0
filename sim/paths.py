"""Closed planar paths for the waypoint scenario: closest point, arc length, tangent heading.

A :class:`PlanarPath` is a closed polyline in the ground plane (world frame, x-y [m]). Every
computation on it is here, once: the closest point to a position (global, for the metrics, or
near a previous arc length, for a follower that must not jump across the path), the point and
the tangent heading at an arc length, the heading change at each vertex, and the corners
(vertices where the heading turns by more than ``CORNER_TURN``).

Arc lengths ``s`` [m] are measured from the first vertex along the path's direction. A follower's
progress is an *unwrapped* arc length: it keeps growing past ``length`` on the second lap;
:meth:`PlanarPath.point_at` and :meth:`PlanarPath.heading_at` accept unwrapped values.

The named paths (:data:`PATHS`) start at the origin heading along +x and turn counter-clockwise,
so a robot standing at the origin with yaw 0 starts on the path, aligned with it:

- ``circle``: radius ``radius`` [m], centre (0, radius), a polygon of ``CIRCLE_SEGMENTS`` sides
  (the polygon is within radius (1 - cos(pi / CIRCLE_SEGMENTS)) = 1e-5 m of the circle of 1 m);
- ``square``: side ``side`` [m], from (-side/2, 0) to (side/2, side), four 90° corners, the first
  one side/2 ahead of the start.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wbmpc.errors import ParameterError

CORNER_TURN = math.radians(20.0)  # [rad], a vertex where the heading turns by more is a corner
CIRCLE_SEGMENTS = 720
PROJECTION_CHUNK = 2048  # points projected at a time on all segments (bounds the memory of project())


def wrap_angle(angle):
    """``angle`` [rad] wrapped to [-pi, pi) (scalar or array)."""
    return (np.asarray(angle, dtype=float) + np.pi) % (2.0 * np.pi) - np.pi


@dataclass(frozen=True, eq=False)
class PlanarPath:
    """A closed polyline in the ground plane.

    Attributes:
        name: what the path is ("circle", "square").
        vertices: (n, 2) vertices, world frame [m], in the order of travel; the path closes from
            the last vertex back to the first (do not repeat the first one).
    """

    name: str
    vertices: np.ndarray

    def __post_init__(self) -> None:
        vertices = np.array(self.vertices, dtype=float)
        if vertices.ndim != 2 or vertices.shape[1] != 2 or len(vertices) < 3 or not np.all(np.isfinite(vertices)):
            raise ParameterError(f"path vertices must be a finite (n >= 3, 2) array [m], got shape {vertices.shape}")
        ends = np.roll(vertices, -1, axis=0)
        lengths = np.linalg.norm(ends - vertices, axis=1)
        if np.any(lengths <= 0.0):
            raise ParameterError(f"path {self.name!r} repeats a vertex (zero-length segment)")
        vertices.setflags(write=False)
        set_ = object.__setattr__
        set_(self, "vertices", vertices)
        set_(self, "_starts", np.concatenate([[0.0], np.cumsum(lengths)[:-1]]))  # arc length of each vertex [m]
        set_(self, "_lengths", lengths)  # (n,) segment lengths [m]
        set_(self, "_directions", (ends - vertices) / lengths[:, None])  # (n, 2) unit tangents
        set_(self, "_headings", np.arctan2(self._directions[:, 1], self._directions[:, 0]))  # (n,) [rad]
        set_(self, "length", float(np.sum(lengths)))

    # ------------------------------------------------------------------ geometry
    @property
    def vertex_arc_lengths(self) -> np.ndarray:
        """Arc length of each vertex [m], in [0, length), shape (n,)."""
        return self._starts.copy()

    @property
    def vertex_turns(self) -> np.ndarray:
        """Signed change of the tangent heading at each vertex [rad] (segment i-1 -> i; > 0 turns
        left), in [-pi, pi), shape (n,): 2 pi / CIRCLE_SEGMENTS on the circle, +-pi/2 at the square's corners."""
        return wrap_angle(self._headings - np.roll(self._headings, 1))

    @property
    def corners(self) -> np.ndarray:
        """Arc lengths [m] of the vertices where the tangent heading turns by more than
        ``CORNER_TURN``, shape (k,) (none on the circle, four on the square)."""
        return self._starts[np.abs(self.vertex_turns) > CORNER_TURN].copy()

    def _segment(self, s) -> tuple[np.ndarray, np.ndarray]:
        """Segment index and distance along it [m] of the (unwrapped) arc lengths ``s``."""
        s = np.asarray(s, dtype=float) % self.length
        index = np.clip(np.searchsorted(self._starts, s, side="right") - 1, 0, len(self._starts) - 1)
        return index, s - self._starts[index]

    def point_at(self, s) -> np.ndarray:
        """Point at arc length ``s`` [m] (unwrapped allowed), world frame [m], shape s.shape + (2,)."""
        index, along = self._segment(s)
        return self.vertices[index] + along[..., None] * self._directions[index]

    def heading_at(self, s) -> np.ndarray:
        """Tangent heading [rad] at arc length ``s`` [m] (unwrapped allowed), from +x, shape s.shape."""
        index, _ = self._segment(s)
        return self._headings[index]

    def _project_on_segments(self, points: np.ndarray, segments: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """For each point, the closest of ``segments``: (position in ``segments``, distance along it [m],
        distance to it [m]) for points (m, 2) and segment indices (k,); shapes (m,)."""
        start = self.vertices[segments]  # (k, 2)
        relative = points[:, None, :] - start[None, :, :]  # (m, k, 2)
        along = np.clip(np.einsum("mkj,kj->mk", relative, self._directions[segments]), 0.0, self._lengths[segments])
        gap = relative - along[..., None] * self._directions[segments][None]
        distance = np.linalg.norm(gap, axis=2)
        best = np.argmin(distance, axis=1)
        rows = np.arange(len(points))
        return best, along[rows, best], distance[rows, best]

    def project(self, points) -> tuple[np.ndarray, np.ndarray]:
        """Closest points of the path to ``points`` (m, 2) [m], world frame.

        Returns:
            (s, distance): arc length of the closest point in [0, length) [m] and the distance to
            it [m], shapes (m,).
        """
        points = np.atleast_2d(np.asarray(points, dtype=float))
        segments = np.arange(len(self.vertices))
        s, distance = np.zeros(len(points)), np.zeros(len(points))
        for first in range(0, len(points), PROJECTION_CHUNK):
            chunk = slice(first, first + PROJECTION_CHUNK)
            best, along, distance[chunk] = self._project_on_segments(points[chunk], segments)
            s[chunk] = (self._starts[best] + along) % self.length
        return s, distance

    def project_near(self, point, s_near: float, behind: float, ahead: float) -> tuple[float, float]:
        """Closest point to ``point`` (2,) [m] among arc lengths in [s_near - behind, s_near + ahead].

        The window keeps a follower's progress from jumping to another part of the path that
        happens to be as close (the far side of a small circle, the start on the last side).

        Args:
            point: position, world frame [m], shape (2,).
            s_near: unwrapped arc length to search around [m] (the previous progress).
            behind, ahead: extent of the search window [m], >= 0.

        Returns:
            (s, distance): unwrapped arc length of the closest point [m] and the distance to it [m].
        """
        n = len(self.vertices)
        low, high = s_near - behind, s_near + ahead

        def unwrapped_segment(s: float) -> int:
            lap = math.floor(s / self.length)
            return lap * n + int(self._segment(s)[0])

        window = np.arange(unwrapped_segment(low), unwrapped_segment(high) + 1)
        best, along, distance = self._project_on_segments(np.asarray(point, dtype=float)[None, :2], window % n)
        segment = int(window[best[0]])
        s = math.floor(segment / n) * self.length + self._starts[segment % n] + float(along[0])
        return s, float(distance[0])


# ---------------------------------------------------------------------- named paths
def circle_path(radius: float) -> PlanarPath:
    """Circle of ``radius`` [m] through the origin, centre (0, radius), counter-clockwise from +x."""
    angle = np.linspace(0.0, 2.0 * np.pi, CIRCLE_SEGMENTS, endpoint=False) - 0.5 * np.pi
    return PlanarPath("circle", np.column_stack([radius * np.cos(angle), radius + radius * np.sin(angle)]))


def square_path(side: float) -> PlanarPath:
    """Square of ``side`` [m] starting at the middle of its bottom side (the origin), heading +x,
    counter-clockwise: the first corner (side/2, 0) is side/2 ahead."""
    half = 0.5 * side
    return PlanarPath("square", np.array([[0.0, 0.0], [half, 0.0], [half, side], [-half, side], [-half, 0.0]]))


PATHS = {"circle": (circle_path, "radius"), "square": (square_path, "side")}  # name -> (builder, its size parameter)


def make_path(name: str, radius: float = 1.0, side: float = 2.0) -> PlanarPath:
    """The named path: ``circle`` of ``radius`` [m] or ``square`` of ``side`` [m] (see the module docstring).

    Raises:
        ParameterError: unknown ``name`` (the message lists the allowed ones), or a size <= 0.
    """
    if name not in PATHS:
        raise ParameterError(f"path={name!r} is unknown (allowed: {', '.join(PATHS)})")
    sizes = {"radius": radius, "side": side}
    for label, value in sizes.items():
        if isinstance(value, bool) or not (isinstance(value, (int, float)) and math.isfinite(value) and 0.0 < value <= 100.0):
            raise ParameterError(f"{label}={value!r} m must be in (0, 100] m")
    builder, size = PATHS[name]
    return builder(float(sizes[size]))


def path_from_parameters(params) -> PlanarPath | None:
    """The path a scenario's parameters describe (``path``, ``radius``, ``side``: the ``waypoints``
    scenario's, or the dict of them a run log keeps), None when they name no path."""
    if params.get("path") is None:
        return None
    return make_path(params["path"], **{size: params[size] for size in ("radius", "side") if size in params})
