"""Shared pieces of every residual: its data buffers and the node data it reads."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin


@dataclass
class DataCollector:
    """What residuals may read at a node.

    Attributes:
        pinocchio: Pinocchio data after the dynamics' calc (kinematics, CoM, Jacobians computed).
        contacts: contact name -> contact data (forces and their derivatives), empty for the
            terminal node.
    """

    pinocchio: pin.Data
    contacts: dict = field(default_factory=dict)


class ResidualData:
    """Buffers of one residual: r (nr,), Rx (nr, ndx), Ru (nr, nu)."""

    def __init__(self, nr: int, ndx: int, nu: int):
        self.r = np.zeros(nr)
        self.Rx = np.zeros((nr, ndx))
        self.Ru = np.zeros((nr, nu))


@dataclass
class HorizonData:
    """What a residual's batched evaluation reads over the N running nodes of a horizon.

    Attributes:
        xs: states (N, nx) of the evaluation; us: controls (N, nu).
        frame_slot: frame id -> slot s of frame_position (N, n_frames, 3) [m, world],
            frame_jacobian (N, n_frames, 3 or 6, nv) (LOCAL_WORLD_ALIGNED: linear rows 0..2, angular
            rows 3..5) and frame_rotation (N, n_frames, 3, 3) (world), computed for the nodes where
            a term needing the frame is active (Jacobians in calcDiff only); the angular rows and
            rotations only when a term declares ``batch_frame_rotations`` (else 3 rows, no rotations).
        com: (N, 3) the centre of mass [m, world] and com_jacobian (N, 3, nv) its Jacobian
            (∂c/∂q in the tangent space, Pinocchio's ``Jcom``), computed by the compiled horizon
            kinematics (:mod:`wbmpc.ocp.kernels.frames`) at the nodes where a term declaring
            ``batch_com`` is active (the Jacobian in calcDiff only); (N, 0) and (N, 0, nv) when no
            term does.
        contact_force: (N, nc_max) the stacked contact forces of each node's contact set, in the
            order of the set (as the node's dynamics computes them: 3D point contacts [N] in
            world-aligned axes, 6D contacts (force [N], torque [N·m]) in the LOCAL contact frame);
            filled when a term reads contact forces.
        contact_force_jacobian: (N, nc_max, ndx + nu) their derivatives [∂λ/∂x, ∂λ/∂u] (calcDiff).
        contact_row: contact name -> (N,) int64, the first row of that contact in the node's
            stacked forces, −1 where the contact is not in the node's set.
        contact_sets: the N nodes' contact sets (tuples of contact names), for messages.
    """

    xs: np.ndarray
    us: np.ndarray
    frame_slot: dict
    frame_position: np.ndarray
    frame_jacobian: np.ndarray
    frame_rotation: np.ndarray
    com: np.ndarray
    com_jacobian: np.ndarray
    contact_force: np.ndarray
    contact_force_jacobian: np.ndarray
    contact_row: dict
    contact_sets: list


def dense_jacobian_pattern(n_rows: int, n_columns: int) -> tuple[np.ndarray, np.ndarray]:
    """(rows, cols) of a dense block: every one of ``n_rows`` rows has the first ``n_columns``
    columns of [Rx Ru], row-major (the ``jacobian_pattern`` of a residual whose rows depend on
    every velocity, or on the whole state and control)."""
    return (np.repeat(np.arange(n_rows, dtype=np.int64), n_columns),
            np.tile(np.arange(n_columns, dtype=np.int64), n_rows))


class BatchedResidual:
    """A residual that declares its own batched evaluation (what
    :class:`~wbmpc.ocp.batched_problem.BatchedShootingProblem` needs of every running term).

    A subclass keeps its reference in ``self._reference`` (1-D array; ``reference`` reads it and
    writes into it, never rebinds it, so the batched problem can make it a row of its stacked
    references with :meth:`bind_reference`) and implements:

    - ``jacobian_pattern()`` -> (rows, cols): the structural nonzeros of [Rx Ru] (columns
      0..ndx−1 the state tangent, ndx.. the control), row-major;
    - ``batch_calc(horizon, mask, references, r)``: r (N, nr) at the nodes with mask (N,);
    - ``batch_calc_diff(horizon, mask, references, values)``: the pattern's values (N, nnz);
    - ``batch_frames``: frame ids whose kinematics it reads from the horizon (default none);
    - ``batch_frame_rotations``: True if it reads their rotations and the angular Jacobian rows
      (then every frame's are computed; default False: positions and linear rows only);
    - ``batch_com``: True if it reads the centre of mass and its Jacobian from the horizon
      (default False);
    - ``batch_signature()``: what must be equal at every node for one batched term.

    Both evaluations call the same compiled rows (:mod:`wbmpc.ocp.kernels.residuals`).
    """

    batch_frames: tuple = ()
    batch_frame_rotations: bool = False
    batch_com: bool = False

    @property
    def reference(self) -> np.ndarray:
        return self._reference

    @reference.setter
    def reference(self, value) -> None:
        self._reference[:] = value

    _reference_owner = None

    def bind_reference(self, storage: np.ndarray, owner=None) -> None:
        """Keep the reference in ``storage`` (same size) from now on, starting from its value.

        ``owner`` (the batched problem holding ``storage``) is told by ``owner.detach()`` when
        another one binds the reference later: it no longer sees the node models' references."""
        previous = self._reference_owner
        if previous is not None and previous is not owner:
            previous.detach()
        storage[:] = self._reference
        self._reference = storage
        self._reference_owner = owner

    def batch_signature(self) -> tuple:
        return (type(self), self.nr, self.batch_frames)
