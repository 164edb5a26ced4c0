"""Metrics of an obstacle run (scenario ``obstacle``): did the robot cross the box, touch it, fall,
and how well did its perception see the box.

Definitions (world frame, the box of ``params["obstacle_truth"]``, crossed along its depth axis):

- ``crossed``: at the end of the run the base and both feet (sole centres) are beyond the box's far
  edge; ``crossing_time`` [s]: the first tick at which they all were (None: never); ``feet_across``: the
  most feet (sole centres) beyond the far edge at any tick (for a fall: 0, it fell before or during the lead
  crossing; 1, astride the box; 2, after both feet had crossed, whatever it fell back onto);
- ``resting_on_obstacle``: a foot or any other part of the robot (shank) touches the box at the
  last tick (``ticks["obstacle_contact"]``, :mod:`sim.falls`);
- ``touched``: any robot-box contact during the run; ``first_touch_time`` [s];
- ``fell``: the run ended in a fall (the runner's fall detector);
- ``success``: crossed, not fallen, not resting on the box, and the run completed (no error);
- the crossing's balance (two feet, the log's ``dcm``, ``feet`` and ``foot_contact`` ticks; None where the event
  did not happen): the DCM along the depth axis minus a sole centre [m] (> 0: the DCM ahead of it) at three events.
  ``lead_touchdown_dcm_margin``: minus the lead foot's, at its touchdown (the first tick a sole centre beyond the far
  edge is on the ground, ``lead_touchdown_time`` [s]); ``trailing_liftoff_dcm_margin``: minus the lead foot's, when
  the other sole rises ``LIFTOFF_HEIGHT`` above the floor after it (``trailing_liftoff_time`` [s]): the body must be
  carried over the lead foot, whose heel bounds the centre of pressure; ``trailing_touchdown_dcm_margin``: minus the
  rear sole's, when the trailing foot is down beyond the far edge (``trailing_touchdown_time`` [s]): < 0, the DCM
  behind both feet with the box behind them;
- perception (when on): ``detected``, ``detection_time`` [s] (first report),
  ``detection_distance`` [m] (the box's near edge ahead of the base, true position, at that time),
  and the last estimate's errors, estimate minus truth [m]: ``height_error``,
  ``near_edge_error``, ``far_edge_error`` (along the box's depth axis from the start, so > 0 is
  farther), ``width_estimate`` [m]; ``perception_scans``, ``perception_rate`` [Hz].
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from sequencer.obstacles import Obstacle

# the crossing's three balance events (the module docstring) and their DCM-margin metrics
CROSSING_EVENTS = ("lead_touchdown", "trailing_liftoff", "trailing_touchdown")
CROSSING_BALANCE_METRICS = tuple(f"{event}_dcm_margin" for event in CROSSING_EVENTS)
LIFTOFF_HEIGHT = 0.05  # [m] a sole centre this far above the floor (z = 0) has lifted off (a heel rocking in a
# double support lifts it 1-2 cm)


def obstacle_from_record(record: dict[str, Any]) -> Obstacle:
    """An :class:`Obstacle` from its plain data in a log (``wbmpc.jsonable.to_jsonable`` of one, extra keys
    such as a detection's ``first_seen`` ignored)."""
    return Obstacle(**{field.name: record[field.name] for field in dataclasses.fields(Obstacle)})


def _crossing_balance(ticks: dict[str, np.ndarray], axis: np.ndarray, far: float) -> dict[str, Any]:
    """The crossing's balance metrics of the module docstring (the world's depth ``axis`` (2,), the box's ``far``
    edge along it [m]); every value None when the log has no DCM or contacts, or not two feet."""
    out: dict[str, Any] = {f"{event}_{kind}": None for event in CROSSING_EVENTS for kind in ("time", "dcm_margin")}
    feet, on_ground, dcm = ticks.get("feet"), ticks.get("foot_contact"), ticks.get("dcm")
    if feet is None or on_ground is None or dcm is None or feet.shape[1] != 2:
        return out
    t = ticks["t"]
    along = feet[:, :, :2] @ axis  # (n, 2) sole centres along the depth axis [m]
    dcm_along = dcm[:, :2] @ axis
    down_beyond = (along > far) & np.asarray(on_ground, dtype=bool)
    if not down_beyond.any():
        return out
    i = int(np.argmax(down_beyond.any(axis=1)))
    lead = int(np.argmax(down_beyond[i]))
    trail = 1 - lead
    out.update(lead_touchdown_time=float(t[i]), lead_touchdown_dcm_margin=float(dcm_along[i] - along[i, lead]))
    lifted = np.flatnonzero(feet[i:, trail, 2] > LIFTOFF_HEIGHT)
    if len(lifted) == 0:
        return out
    j = i + int(lifted[0])
    out.update(trailing_liftoff_time=float(t[j]), trailing_liftoff_dcm_margin=float(dcm_along[j] - along[j, lead]))
    landed = np.flatnonzero(down_beyond[j:, trail])
    if len(landed) == 0:
        return out
    k = j + int(landed[0])
    out.update(trailing_touchdown_time=float(t[k]),
               trailing_touchdown_dcm_margin=float(dcm_along[k] - np.min(along[k])))
    return out


def obstacle_metrics(log) -> dict[str, Any]:
    """The metrics of the module docstring for a :class:`sim.log.RunLog` whose params hold
    ``obstacle_truth`` (empty dict otherwise)."""
    truths = log.params.get("obstacle_truth") or []
    ticks = log.ticks
    if not truths or len(ticks.get("t", ())) == 0:
        return {}
    truth = obstacle_from_record(truths[0])
    t = ticks["t"]
    axis = truth.axes[0]
    far = float(truth.center @ axis + 0.5 * truth.depth)  # far edge along the depth axis [m]
    near = far - truth.depth
    base = ticks["x"][:, :2] @ axis
    feet = ticks["feet"][:, :, :2] @ axis  # (n, n_feet)
    beyond = (base > far) & np.all(feet > far, axis=1)
    contact = ticks.get("obstacle_contact", np.zeros((len(t), 1), dtype=bool))
    touching = np.any(contact, axis=1)
    crossed = bool(beyond[-1])
    resting = bool(touching[-1])
    fell = log.status == "fell"
    metrics: dict[str, Any] = {
        "obstacle_height": truth.height,
        "obstacle_depth": truth.depth,
        "obstacle_near_edge": near,
        "crossed": crossed,
        "crossing_time": float(t[np.argmax(beyond)]) if beyond.any() else None,
        "feet_across": int(np.max(np.sum(feet > far, axis=1))),
        "touched": bool(touching.any()),
        "first_touch_time": float(t[np.argmax(touching)]) if touching.any() else None,
        "resting_on_obstacle": resting,
        "success": crossed and not fell and not resting and log.status == "completed",
        **_crossing_balance(ticks, axis, far),
    }
    perception = log.params.get("perception")
    if perception is None:
        return metrics
    metrics["perception_scans"] = perception["n_scans"]
    metrics["perception_rate"] = perception["rate"]
    detections = [obstacle_from_record(d) for d in perception["detections"]]
    metrics["detected"] = bool(detections)
    if not detections:
        return metrics
    k = int(np.argmin([np.linalg.norm(d.center - truth.center) for d in detections]))
    estimate, first_seen = detections[k], perception["detections"][k]["first_seen"]
    i = min(int(np.searchsorted(t, first_seen)), len(t) - 1)
    estimated_far = float(estimate.center @ axis + 0.5 * abs(estimate.axes[0] @ axis) * estimate.depth)
    estimated_near = float(estimate.center @ axis - 0.5 * abs(estimate.axes[0] @ axis) * estimate.depth)
    metrics.update(
        detection_time=float(first_seen),
        detection_distance=float(near - base[i]),
        height_error=float(estimate.height - truth.height),
        near_edge_error=estimated_near - near,
        far_edge_error=estimated_far - far,
        width_estimate=float(estimate.width),
    )
    return metrics
