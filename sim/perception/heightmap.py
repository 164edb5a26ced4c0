"""A ground-height map with memory: the returns accumulated in square cells of the world's xy plane.

Every return (a world point) falls in the cell ``floor(x / cell_size), floor(y / cell_size)``; a
cell keeps the number of its returns, their mean height, the bounding box of their xy
positions and the bounding box of those above a height given with them (the returns on an
obstacle: a cell straddling the edge of a box also holds ground returns, which must not move the
edge). Nothing is forgotten: a box the robot has walked up to stays in the map after it left
the rays' field of view. Cells no ray has hit are unknown (NaN).
"""

from __future__ import annotations

import numpy as np

from wbmpc.errors import ParameterError

_INITIAL_CELLS = 1024
# a cell's key: ix * 2^32 + (iy + 2^31), increasing with (ix, iy) in lexicographic order (|ix|, |iy| < 2^31: within
# 2^31 cells of the origin, 4e7 m at 2 cm)
_KEY_BASE = np.int64(1) << np.int64(32)
_KEY_OFFSET = np.int64(1) << np.int64(31)


def cell_key(cells: np.ndarray) -> np.ndarray:
    """One int64 key per cell (ix, iy) of ``cells`` (m, 2), in the cells' lexicographic order, shape (m,)."""
    cells = np.asarray(cells, dtype=np.int64)
    return cells[:, 0] * _KEY_BASE + (cells[:, 1] + _KEY_OFFSET)


class HeightMap:
    """Cells of side ``cell_size`` [m] (world frame) with the statistics of their returns.

    Attributes (one row per known cell, the first :attr:`n_cells` rows):
        keys: integer cell indices (ix, iy), shape (n, 2).
        count: returns per cell.
        height: mean height of the returns [m].
        bounds: (x_min, x_max, y_min, y_max) of the returns [m], shape (n, 4).
        high_bounds: the same for the returns above the ``high_above`` height they were added with
            [m], shape (n, 4); (inf, -inf, inf, -inf) in a cell without any.
    """

    def __init__(self, cell_size: float) -> None:
        if not (np.isfinite(cell_size) and cell_size > 0):
            raise ParameterError(f"cell_size={cell_size} m must be > 0")
        self.cell_size = float(cell_size)
        self.n_cells = 0
        # the known cells' keys (cell_key) in increasing order and the row of each: a scan's cells are
        # looked up by one searchsorted (cells sorted by ix, then iy)
        self._sorted_keys = np.zeros(0, dtype=np.int64)
        self._sorted_rows = np.zeros(0, dtype=np.int64)
        self._keys = np.zeros((_INITIAL_CELLS, 2), dtype=np.int64)
        self._count = np.zeros(_INITIAL_CELLS, dtype=np.int64)
        self._sum_z = np.zeros(_INITIAL_CELLS)
        self._bounds = np.zeros((_INITIAL_CELLS, 4))
        self._high_bounds = np.zeros((_INITIAL_CELLS, 4))
        self._centers = np.zeros((_INITIAL_CELLS, 2))
        self.n_high_added = 0  # returns above ``high_above`` added by the last :meth:`add`

    # ------------------------------------------------------------------ views of the known cells
    @property
    def keys(self) -> np.ndarray:
        return self._keys[: self.n_cells]

    @property
    def count(self) -> np.ndarray:
        return self._count[: self.n_cells]

    @property
    def height(self) -> np.ndarray:
        return self._sum_z[: self.n_cells] / self._count[: self.n_cells]

    @property
    def bounds(self) -> np.ndarray:
        return self._bounds[: self.n_cells]

    @property
    def high_bounds(self) -> np.ndarray:
        return self._high_bounds[: self.n_cells]

    def height_of(self, rows: np.ndarray) -> np.ndarray:
        """Mean return height [m] of the cells at ``rows`` (k,), shape (k,)."""
        return self._sum_z[rows] / self._count[rows]

    def centers(self) -> np.ndarray:
        """Centres (x, y) of the known cells [m], shape (n, 2)."""
        return self._centers[: self.n_cells]

    # ------------------------------------------------------------------ updates and queries
    def cells_of(self, points_xy: np.ndarray) -> np.ndarray:
        """Integer cell indices (ix, iy) of ``points_xy`` (m, 2) [m], shape (m, 2)."""
        return np.floor(np.asarray(points_xy, dtype=float) / self.cell_size).astype(np.int64)

    def add(self, points_world: np.ndarray, high_above: float = np.inf) -> None:
        """Accumulate returns ``points_world`` (m, 3) [m] into their cells; those higher than
        ``high_above`` [m] also into the cells' :attr:`high_bounds`. Cells seen for the first time get
        the next rows in the order of their indices (ix, then iy)."""
        points = np.asarray(points_world, dtype=float).reshape(-1, 3)
        self.n_high_added = 0
        if len(points) == 0:
            return
        unique, inverse = np.unique(cell_key(self.cells_of(points[:, :2])), return_inverse=True)
        rows = self._rows(unique)[inverse.reshape(-1)]
        np.add.at(self._count, rows, 1)
        np.add.at(self._sum_z, rows, points[:, 2])
        high = points[:, 2] > high_above
        self.n_high_added = int(np.count_nonzero(high))
        for column, (coordinate, reduce) in enumerate(((0, np.minimum), (0, np.maximum), (1, np.minimum), (1, np.maximum))):
            reduce.at(self._bounds[:, column], rows, points[:, coordinate])
            reduce.at(self._high_bounds[:, column], rows[high], points[high, coordinate])

    def _find(self, keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Where the cells ``keys`` (k,) are, or would go, in the sorted keys (k,), and which are known (k,) bool."""
        position = np.searchsorted(self._sorted_keys, keys)
        known = position < len(self._sorted_keys)
        known[known] = self._sorted_keys[position[known]] == keys[known]
        return position, known

    def _rows(self, keys: np.ndarray) -> np.ndarray:
        """Rows of the cells ``keys`` (k,) (increasing, distinct), the unknown ones added in that order."""
        position, known = self._find(keys)
        rows = np.empty(len(keys), dtype=np.int64)
        rows[known] = self._sorted_rows[position[known]]
        new = ~known
        n_new = int(np.count_nonzero(new))
        if n_new:
            while self.n_cells + n_new > len(self._count):
                self._grow()
            rows[new] = np.arange(self.n_cells, self.n_cells + n_new)
            ix, iy = np.divmod(keys[new], _KEY_BASE)
            iy -= _KEY_OFFSET
            added = slice(self.n_cells, self.n_cells + n_new)
            self._keys[added, 0], self._keys[added, 1] = ix, iy
            self._centers[added, 0] = (ix + 0.5) * self.cell_size
            self._centers[added, 1] = (iy + 0.5) * self.cell_size
            self._bounds[added] = self._high_bounds[added] = (np.inf, -np.inf, np.inf, -np.inf)
            self._sorted_keys = np.insert(self._sorted_keys, position[new], keys[new])
            self._sorted_rows = np.insert(self._sorted_rows, position[new], rows[new])
            self.n_cells += n_new
        return rows

    def _grow(self) -> None:
        size = 2 * len(self._count)
        self._keys = np.resize(self._keys, (size, 2))
        self._count = np.concatenate([self._count, np.zeros(size - len(self._count), dtype=np.int64)])
        self._sum_z = np.concatenate([self._sum_z, np.zeros(size - len(self._sum_z))])
        self._bounds = np.resize(self._bounds, (size, 4))
        self._high_bounds = np.resize(self._high_bounds, (size, 4))
        self._centers = np.resize(self._centers, (size, 2))

    def rows_near(self, center_xy, radius: float) -> np.ndarray:
        """Rows of the known cells whose centres are within ``radius`` [m] of ``center_xy`` (2,) [m], in
        increasing order, shape (k,): those within ``radius`` along x (one pass over the centres' x), then by
        their ``np.hypot`` distance."""
        center = np.asarray(center_xy, dtype=float)
        x = self._centers[: self.n_cells, 0]
        rows = np.flatnonzero(np.abs(x - center[0]) <= radius)
        offset = self._centers[rows] - center
        return rows[np.hypot(offset[:, 0], offset[:, 1]) <= radius]

    def height_at(self, points_xy) -> np.ndarray:
        """Mean return height [m] of the cells holding ``points_xy`` (..., 2); NaN where unknown."""
        xy = np.asarray(points_xy, dtype=float)
        position, known = self._find(cell_key(self.cells_of(xy.reshape(-1, 2))))
        out = np.full(len(known), np.nan)
        out[known] = self.height_of(self._sorted_rows[position[known]])
        return out.reshape(xy.shape[:-1])

    def profile(self, origin_xy, heading_yaw: float, distances) -> np.ndarray:
        """The height map along the heading: heights [m] at ``distances`` (k,) [m] from ``origin_xy``
        in the direction ``heading_yaw`` [rad], world frame; NaN where unknown."""
        direction = np.array([np.cos(heading_yaw), np.sin(heading_yaw)])
        points = np.asarray(origin_xy, dtype=float) + np.asarray(distances, dtype=float)[:, None] * direction
        return self.height_at(points)
