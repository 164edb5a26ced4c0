"""Terrain estimate: from scans and the measured base pose, a height map and the obstacles on it.

Pure numpy. Each :meth:`TerrainEstimator.update`:

1. projects the scan's returns into the world with the *measured* base pose (``Measurement.x``,
   never the simulator's state) and drops those closer than ``min_ground_distance`` to the base,
   horizontally, and those within ``self_filter_radius`` of the robot's leg segments given with
   the scan (the robot's own legs: see :mod:`sim.perception.rangefinder`);
2. accumulates them in the :class:`~sim.perception.heightmap.HeightMap` (memory: the map keeps what
   the rays saw, so a box stays known once it has left their field of view);
3. estimates the ground level, the median height of the cells within ``ground_radius`` of the base
   (twice: the second time without the cells more than ``obstacle_min_height`` above the first);
4. marks the cells whose mean height is more than ``obstacle_min_height`` above the ground (and
   that hold at least ``min_cell_returns`` returns), groups
   them (touching bins of side ``cluster_gap / 2``, transitively: :func:`_groups`) and reports each group holding
   at least ``min_returns`` returns as a :class:`sequencer.obstacles.Obstacle`:

   - its depth axis (``obstacle_axis``): ``"heading"``, the robot's measured heading when the group
     was first reported (the obstacle's own orientation is not estimated: a box across the path is
     crossed along it); ``"near_edge"``, the normal of the box's near edge fitted to its cells'
     returns at every estimate (:func:`near_edge_yaw`), that heading when the fit is not trusted;
   - near / far edge and width: the extreme positions of its cells' returns above the ground by
     ``obstacle_min_height`` (the ground level of the previous scan), along and across that axis.
     The near edge is seen on the box's front face and is sharp; the far edge is the last return
     on the top, short of the true edge by up to the rays' spacing on the top; the width is what
     the rays' fan saw (a lower bound of a box wider than the fan);
   - height: the median of its top cells' mean heights, minus the ground level (top cells: those
     at least half as high as the group's 90th percentile; the cells of the front face, lower,
     are left out).

   A group is matched to an obstacle already reported when its centroid lies in that obstacle's
   footprint grown by ``cluster_gap`` (groups matching the same obstacle are merged, and so are two
   reported obstacles one of which has its centre in the other's grown footprint); the estimate is
   refined with every scan.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robots.conventions import base_yaw
from sequencer.obstacles import Obstacle
from sim.perception.heightmap import HeightMap
from sim.perception.scan import Scan
from wbmpc.walking.perception_config import PerceptionConfig

GROUND_CHANGE = 1e-4  # [m], a ground level change that re-estimates the obstacles without new returns on them

# The near-edge fit (obstacle_axis = "near_edge", :func:`near_edge_yaw`)
NEAR_EDGE_BIN_CELLS = 3  # [cells] width of the bins across the heading, in map cells (6 cm at 2 cm cells)
NEAR_EDGE_MIN_SPAN = 0.3  # [m] the near edge's points must span this much across the heading ...
NEAR_EDGE_MIN_BINS = 4  # ... in at least this many bins; else the heading is kept
NEAR_EDGE_MAX_CORRECTION = 0.4  # [rad] a fitted axis farther than this from the heading is not trusted: heading kept


@dataclass
class ObstacleTrack:
    """One reported obstacle and its history.

    Attributes:
        first_seen: time it was first reported [s].
        heading: the measured base heading at ``first_seen`` [rad], world frame (the reference of the
            near-edge fit and its fallback).
        obstacle: the current estimate.
        n_returns: returns in its cells [-].
        n_cells: cells [-].
    """

    first_seen: float
    heading: float
    obstacle: Obstacle
    n_returns: int
    n_cells: int

    @property
    def yaw(self) -> float:
        """Its depth axis, the current estimate's [rad], world frame: ``heading`` with ``obstacle_axis =
        "heading"``, the near edge's normal (refitted at every estimate) with ``"near_edge"``."""
        return self.obstacle.yaw


class TerrainEstimator:
    """The height map and the obstacles found on it (see the module docstring).

    Attributes:
        map: the :class:`HeightMap`.
        tracks: the obstacles reported so far, in the order they were first reported.
        ground: the last ground level [m] (None before the first return).
        n_updates, n_returns, n_dropped_near: scans processed, returns received, returns dropped
            as too close to the robot (its base or its legs).
    """

    def __init__(self, config: PerceptionConfig) -> None:
        self.config = config
        self.map = HeightMap(config.cell_size)
        self.tracks: list[ObstacleTrack] = []
        self.ground: float | None = None
        self.n_updates = self.n_returns = self.n_dropped_near = 0

    @property
    def obstacles(self) -> tuple[Obstacle, ...]:
        """The obstacles reported so far (current estimates), in the order they were first reported."""
        return tuple(track.obstacle for track in self.tracks)

    def update(self, scan: Scan, x_measured: np.ndarray, robot_segments: np.ndarray | None = None
               ) -> tuple[Obstacle, ...]:
        """Add ``scan``, taken at the measured state ``x_measured`` (Pinocchio convention; only the
        base pose q[0:7] is read), and return the obstacles reported so far.

        Args:
            robot_segments: the robot's own segments (legs), world frame [m], shape (k, 2, 3) (start and
                end points), placed by the measured configuration; returns within
                ``self_filter_radius`` of one are dropped (None: none given).
        """
        x = np.asarray(x_measured, dtype=float)
        self.n_updates += 1
        points = scan.points_world(x)
        self.n_returns += len(points)
        near = np.hypot(points[:, 0] - x[0], points[:, 1] - x[1]) < self.config.min_ground_distance
        if robot_segments is not None and len(robot_segments) and self.config.self_filter_radius > 0:
            near |= segment_distance(points, robot_segments) < self.config.self_filter_radius
        self.n_dropped_near += int(np.count_nonzero(near))
        ground = 0.0 if self.ground is None else self.ground  # the last scan's level (flat ground at first)
        self.map.add(points[~near], high_above=ground + self.config.obstacle_min_height)
        if self.map.n_cells == 0:
            return self.obstacles
        previous, self.ground = self.ground, self._ground_level(x[:2])
        # the obstacles change only with new returns on them or with the ground level
        changed = previous is None or abs(self.ground - previous) > GROUND_CHANGE
        if self.ground is not None and (self.map.n_high_added > 0 or changed):
            self._detect(scan.t, float(base_yaw(x[3:7])))
        return self.obstacles

    def _ground_level(self, base_xy: np.ndarray) -> float | None:
        local = self.map.rows_near(base_xy, self.config.ground_radius)
        if len(local) == 0:
            return self.ground
        heights = self.map.height_of(local)
        first = float(np.median(heights))
        low = heights <= first + self.config.obstacle_min_height
        return float(np.median(heights[low])) if low.any() else first

    def _detect(self, t: float, heading: float) -> None:
        config = self.config
        high = np.flatnonzero((self.map.height - self.ground > config.obstacle_min_height)
                              & (self.map.count >= config.min_cell_returns))
        if len(high) == 0:
            return
        groups = _groups(self.map.centers()[high], config.cluster_gap)
        assigned: dict[int, list[np.ndarray]] = {}
        new: list[np.ndarray] = []
        count = self.map.count
        for group in groups:
            cells = high[group]
            centroid = np.average(self.map.centers()[cells], axis=0, weights=count[cells])
            match = next((k for k, track in enumerate(self.tracks)
                          if track.obstacle.contains(centroid, margin=config.cluster_gap)), None)
            if match is None:
                new.append(cells)
            else:
                assigned.setdefault(match, []).append(cells)
        for k, parts in assigned.items():
            track = self.tracks[k]
            estimate = self._estimate(np.concatenate(parts), track.heading)
            if estimate is not None:
                track.obstacle, track.n_returns, track.n_cells = estimate
        for cells in new:
            estimate = self._estimate(cells, heading)
            if estimate is not None:
                obstacle, n_returns, n_cells = estimate
                self.tracks.append(ObstacleTrack(t, heading, obstacle, n_returns, n_cells))
        self._merge_overlapping()

    def _merge_overlapping(self) -> None:
        """Drop a track whose centre lies in the footprint (grown by ``cluster_gap``) of a track with more
        returns (a part of one box first seen apart, e.g. its front face below a nearer box's shadow);
        the kept track takes the earlier first report time."""
        kept: list[ObstacleTrack] = []
        for track in sorted(self.tracks, key=lambda tr: -tr.n_returns):
            host = next((k for k in kept if k.obstacle.contains(track.obstacle.center, margin=self.config.cluster_gap)),
                        None)
            if host is None:
                kept.append(track)
            else:
                host.first_seen = min(host.first_seen, track.first_seen)
        self.tracks = sorted(kept, key=lambda tr: tr.first_seen)

    def _estimate(self, cells: np.ndarray, heading: float) -> tuple[Obstacle, int, int] | None:
        """The obstacle of ``cells`` (rows of the map), or None below ``min_returns``; its depth axis is
        ``heading`` [rad] (world frame) or, with ``obstacle_axis = "near_edge"``, the near edge's normal
        fitted to the cells' returns above the ground (:func:`near_edge_yaw`; ``heading`` when not trusted)."""
        n_returns = int(self.map.count[cells].sum())
        if n_returns < self.config.min_returns:
            return None
        bounds = self.map.high_bounds[cells]
        seen_high = np.isfinite(bounds[:, 0])
        yaw = heading
        if self.config.obstacle_axis == "near_edge":
            fitted = near_edge_yaw(bounds[seen_high], heading, NEAR_EDGE_BIN_CELLS * self.config.cell_size)
            yaw = heading if fitted is None else fitted
        bounds = np.where(seen_high[:, None], bounds, self.map.bounds[cells])  # a cell made high by its mean only
        corners = _box_corners(bounds)
        axes = np.array([[np.cos(yaw), np.sin(yaw)], [-np.sin(yaw), np.cos(yaw)]])
        local = corners @ axes.T
        low, high = local.min(axis=0), local.max(axis=0)
        size = np.maximum(high - low, self.config.cell_size)
        center = 0.5 * (low + high) @ axes
        heights = self.map.height[cells] - self.ground
        top = heights >= 0.5 * np.percentile(heights, 90)  # the top's cells, not those of the front face below it
        height = float(np.median(heights[top]))
        return Obstacle(center=center, yaw=yaw, depth=size[0], width=size[1], height=height), n_returns, len(cells)


def near_edge_yaw(high_bounds: np.ndarray, heading: float, bin_width: float) -> float | None:
    """The normal of an obstacle's near edge (the face toward the robot) [rad], world frame, or None
    when the fit is not trusted.

    In the frame of ``heading`` [rad] (along it, across it to the left), the corners of the cells'
    bounding boxes of returns above the ground (``high_bounds``: x_min, x_max, y_min, y_max, world
    frame [m], shape (n, 4), finite rows) are binned across the heading (bins of ``bin_width`` [m]);
    each bin keeps its nearest corner along the heading (the front face: nearer than the top behind
    it), and a line along = c + m * across is fitted to those points by Theil-Sen (the median of the
    slopes of the pairs at least a bin apart across: robust to the bins whose nearest point is on the
    top or a side face). The edge's normal is then ``heading - atan(m)``.

    None (keep the heading) when the points span less than ``NEAR_EDGE_MIN_SPAN`` across or fill fewer
    than ``NEAR_EDGE_MIN_BINS`` bins, or when the normal is more than ``NEAR_EDGE_MAX_CORRECTION`` from
    the heading.
    """
    corners = _box_corners(np.asarray(high_bounds, dtype=float).reshape(-1, 4))
    along = corners @ np.array([np.cos(heading), np.sin(heading)])
    across = corners @ np.array([-np.sin(heading), np.cos(heading)])
    bins = np.floor(across / bin_width).astype(np.int64)
    order = np.lexsort((along, bins))  # by bin, then nearest first
    _, first = np.unique(bins[order], return_index=True)
    edge_along, edge_across = along[order][first], across[order][first]
    if len(first) < NEAR_EDGE_MIN_BINS or np.ptp(edge_across) < NEAR_EDGE_MIN_SPAN:
        return None
    i, j = np.triu_indices(len(first), 1)
    apart = np.abs(edge_across[j] - edge_across[i]) >= bin_width
    if not apart.any():
        return None
    slope = float(np.median((edge_along[j] - edge_along[i])[apart] / (edge_across[j] - edge_across[i])[apart]))
    correction = -float(np.arctan(slope))
    return heading + correction if abs(correction) <= NEAR_EDGE_MAX_CORRECTION else None


def _box_corners(bounds: np.ndarray) -> np.ndarray:
    """The four corners (x, y) [m] of each of the boxes ``bounds`` (n, 4) (x_min, x_max, y_min, y_max),
    shape (4 n, 2), world frame."""
    x_min, x_max, y_min, y_max = bounds.T
    return np.stack([np.column_stack([x_min, y_min]), np.column_stack([x_max, y_min]),
                     np.column_stack([x_max, y_max]), np.column_stack([x_min, y_max])]).reshape(-1, 2)


def segment_distance(points: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """Distance [m] from each of ``points`` (m, 3) to the nearest of ``segments`` (k, 2, 3), shape (m,)."""
    start, end = segments[:, 0], segments[:, 1]
    along = end - start  # (k, 3)
    length2 = np.maximum(np.einsum("kd,kd->k", along, along), 1e-12)
    relative = points[:, None, :] - start[None]  # (m, k, 3)
    s = np.clip(np.einsum("mkd,kd->mk", relative, along) / length2, 0.0, 1.0)
    closest = start[None] + s[..., None] * along[None]
    return np.min(np.linalg.norm(points[:, None, :] - closest, axis=2), axis=1)


def _groups(points_xy: np.ndarray, gap: float) -> list[np.ndarray]:
    """Indices of ``points_xy`` (n, 2) grouped by proximity: the points fall in square bins of side
    ``gap / 2`` [m], and bins that touch (8-neighbours) share a group, transitively. Two points of one
    group step by at most ``gap`` from bin to bin (bins' centres); points farther apart than ``gap``
    with nothing between them are in different groups."""
    bins = np.floor(np.asarray(points_xy) / (0.5 * gap)).astype(np.int64)
    unique, inverse = np.unique(bins, axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    index = {(int(i), int(j)): k for k, (i, j) in enumerate(unique)}
    label = np.full(len(unique), -1)
    n_groups = 0
    for start in range(len(unique)):
        if label[start] >= 0:
            continue
        label[start], stack = n_groups, [start]
        while stack:
            i, j = unique[stack.pop()]
            for di in (-1, 0, 1):
                for dj in (-1, 0, 1):
                    k = index.get((int(i) + di, int(j) + dj))
                    if k is not None and label[k] < 0:
                        label[k] = n_groups
                        stack.append(k)
        n_groups += 1
    point_label = label[inverse]
    return [np.flatnonzero(point_label == g) for g in range(n_groups)]
