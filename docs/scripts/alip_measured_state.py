"""Which measured ALIP state predicts the G1's motion better in closed loop: the exact angular momentum about the
stance contact (wbmpc.walking.alip_state) or the paper's eqs. 14-15 without the I ω terms (the planner's own).

For every single-support stance of a walking log (``run_scenario(..., out=DIR)``), from the state measured at
several times after the double support, the ALIP (τ = 0, the planner's model) predicts the CoM position
relative to the stance contact at the measured touchdown that ends the stance; the error against the measured
position is printed per estimate (median and 90th percentile of |error| [mm], x and y, heading frame). Both
estimates see the same motion: only the angular momentum they start the prediction from differs.

    python docs/scripts/alip_measured_state.py DIR [--double-support 0.1]
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from robots import load_robot
from sequencer.alip import AlipParams
from sequencer.alip.planner import alip_state_about_contact
from sequencer.planner import StanceState
from sim import load_run
from wbmpc.walking.alip_state import contact_angular_momentum

PREDICTION_STARTS = (0.0, 0.05, 0.1, 0.15)  # [s] after the end of the double support
MIN_PREDICTION = 0.05  # [s]: predictions shorter than this are skipped


def stances(replans: dict) -> list[tuple[float, float, str, np.ndarray, float]]:
    """(start [s], end [s] = the next measured touchdown, foot, position (2,), yaw) of every complete stance."""
    switched = np.flatnonzero(replans["stance_switched"] > 0)
    out = []
    for i, j in zip(switched[:-1], switched[1:]):
        foot = "left" if replans["stance_foot"][i] == 0 else "right"
        out.append((float(replans["t_stance_start"][i]), float(replans["t"][j]), foot,
                    np.array([replans["stance_x"][i], replans["stance_y"][i]]), float(replans["stance_yaw"][i])))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("directory")
    parser.add_argument("--double-support", type=float, default=0.1, help="skipped after each touchdown [s]")
    args = parser.parse_args()
    log = load_run(args.directory)
    robot = load_robot(log.robot)
    model = robot.pinocchio_model
    data = model.createData()
    alip = AlipParams.preset(log.robot).model
    t, x, feet = log.ticks["t"], log.ticks["x"], log.ticks["feet"]
    nq = model.nq
    feet_order = tuple(robot.foot_frames)

    def states(k: int, stance: StanceState, foot: str) -> tuple[np.ndarray, np.ndarray]:
        contact = np.array([*stance.position, feet[k, feet_order.index(foot), 2]])
        centroidal = contact_angular_momentum(model, data, x[k, :nq], x[k, nq:], contact)
        exact = alip_state_about_contact(alip, stance, centroidal.com, centroidal.com_velocity,
                                         centroidal.angular_momentum_contact)
        approximate = alip_state_about_contact(alip, stance, centroidal.com, centroidal.com_velocity)
        return exact, approximate

    errors = {"exact": [], "approximate": []}
    for start, end, foot, position, yaw in stances(log.replans):
        stance = StanceState(foot, position, yaw, start)
        k_end = int(np.searchsorted(t, end))
        if k_end >= len(t):
            continue
        final = states(k_end, stance, foot)[0]  # p is the same in both
        for offset in PREDICTION_STARTS:
            t0 = start + args.double_support + offset
            if end - t0 < MIN_PREDICTION:
                continue
            k0 = int(np.searchsorted(t, t0))
            for name, state in zip(("exact", "approximate"), states(k0, stance, foot)):
                predicted = alip.flow(state, (0.0, 0.0), t[k_end] - t[k0])
                errors[name].append((predicted[[0, 2]] - final[[0, 2]]))
    summary = {"directory": args.directory, "predictions": len(errors["exact"])}
    for name, values in errors.items():
        values = np.abs(np.array(values)) * 1e3
        summary[name] = {"median_mm": np.round(np.median(values, axis=0), 1).tolist(),
                         "p90_mm": np.round(np.percentile(values, 90, axis=0), 1).tolist()}
    print(json.dumps(summary))


if __name__ == "__main__":
    main()
