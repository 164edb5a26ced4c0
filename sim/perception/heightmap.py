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
        self._index: dict[tuple[int, int], int] = {}
        self.n_cells = 0
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

    def centers(self) -> np.ndarray:
        """Centres (x, y) of the known cells [m], shape (n, 2)."""
        return self._centers[: self.n_cells]

    # ------------------------------------------------------------------ updates and queries
    def add(self, points_world: np.ndarray, high_above: float = np.inf) -> None:
        """Accumulate returns ``points_world`` (m, 3) [m] into their cells; those higher than
        ``high_above`` [m] also into the cells' :attr:`high_bounds`."""
        points = np.asarray(points_world, dtype=float).reshape(-1, 3)
        self.n_high_added = 0
        if len(points) == 0:
            return
        cells = np.floor(points[:, :2] / self.cell_size).astype(np.int64)
        unique, inverse = np.unique(cells, axis=0, return_inverse=True)
        inverse = inverse.reshape(-1)
        rows = np.array([self._row(int(ix), int(iy)) for ix, iy in unique])[inverse]
        np.add.at(self._count, rows, 1)
        np.add.at(self._sum_z, rows, points[:, 2])
        high = points[:, 2] > high_above
        self.n_high_added = int(np.count_nonzero(high))
        for column, (coordinate, reduce) in enumerate(((0, np.minimum), (0, np.maximum), (1, np.minimum), (1, np.maximum))):
            reduce.at(self._bounds[:, column], rows, points[:, coordinate])
            reduce.at(self._high_bounds[:, column], rows[high], points[high, coordinate])

    def _row(self, ix: int, iy: int) -> int:
        row = self._index.get((ix, iy))
        if row is not None:
            return row
        if self.n_cells == len(self._count):
            self._grow()
        row = self.n_cells
        self._index[(ix, iy)] = row
        self._keys[row] = (ix, iy)
        self._centers[row] = ((ix + 0.5) * self.cell_size, (iy + 0.5) * self.cell_size)
        self._bounds[row] = self._high_bounds[row] = (np.inf, -np.inf, np.inf, -np.inf)
        self.n_cells += 1
        return row

    def _grow(self) -> None:
        size = 2 * len(self._count)
        self._keys = np.resize(self._keys, (size, 2))
        self._count = np.concatenate([self._count, np.zeros(size - len(self._count), dtype=np.int64)])
        self._sum_z = np.concatenate([self._sum_z, np.zeros(size - len(self._sum_z))])
        self._bounds = np.resize(self._bounds, (size, 4))
        self._high_bounds = np.resize(self._high_bounds, (size, 4))
        self._centers = np.resize(self._centers, (size, 2))

    def height_at(self, points_xy) -> np.ndarray:
        """Mean return height [m] of the cells holding ``points_xy`` (..., 2); NaN where unknown."""
        xy = np.asarray(points_xy, dtype=float)
        cells = np.floor(xy.reshape(-1, 2) / self.cell_size).astype(np.int64)
        height = self.height
        out = np.array([height[self._index[key]] if (key := (int(ix), int(iy))) in self._index else np.nan
                        for ix, iy in cells])
        return out.reshape(xy.shape[:-1])

    def profile(self, origin_xy, heading_yaw: float, distances) -> np.ndarray:
        """The height map along the heading: heights [m] at ``distances`` (k,) [m] from ``origin_xy``
        in the direction ``heading_yaw`` [rad], world frame; NaN where unknown."""
        direction = np.array([np.cos(heading_yaw), np.sin(heading_yaw)])
        points = np.asarray(origin_xy, dtype=float) + np.asarray(distances, dtype=float)[:, None] * direction
        return self.height_at(points)
