"""RecedingHorizonMPC(horizon_end="phase"): a node entering the horizon takes the control of the latest node in the same
gait phase (its contact set entered from the same other one), else ``entering_controls``."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from wbmpc.errors import ParameterError
from wbmpc.ocp.mpc import MPCSolution, RecedingHorizonMPC, _phase_keys, _same_phase

NX, NU = 1, 1
L, R, D = ("left",), ("right",), ("left", "right")


class _Model:
    """A node whose contact set is ``key``; its dynamics keep the state (xnext = x)."""

    def __init__(self, key):
        self.differential = SimpleNamespace(active_key=key)

    def calc(self, data, x, u):
        data.xnext = np.array(x, dtype=float)


def _mpc(keys, horizon_end, entering=None):
    problem = SimpleNamespace(T=len(keys), nx=NX, ndx=NX, nu=NU, running_models=[_Model(k) for k in keys],
                              running_datas=[SimpleNamespace(xnext=None) for _ in keys])
    return RecedingHorizonMPC(problem, 0.02, solver=SimpleNamespace(), horizon_end=horizon_end,
                              entering_controls=entering)


def _guess(mpc, us_last):
    """The warm start one node after a solution whose controls were ``us_last`` (node j's control = its index)."""
    n = len(us_last)
    last = MPCSolution(ok=True, status="max_iter", iterations=1, cost=1.0, solve_time=0.0, t=0.0,
                       xs=np.zeros((n + 1, NX)), us=np.asarray(us_last, dtype=float).reshape(n, NU),
                       K=np.zeros((n, NU, NX)))
    mpc.last_good = last
    return mpc.warm_start(0.02, np.zeros(NX))[1][:, 0]


def test_phase_keys_name_the_contact_set_entered_from():
    keys = _phase_keys([L, L, D, D, R, R, D, L])
    assert keys == [(L, None), (L, None), (D, L), (D, L), (R, D), (R, D), (D, R), (L, D)]
    assert _same_phase((D, L), (D, L)) and not _same_phase((D, L), (D, R))
    assert _same_phase((L, None), (L, D))  # the horizon's first run: its predecessor is unknown, any matches
    assert not _same_phase((L, None), (R, D))


def test_an_entering_double_support_is_not_filled_from_the_other_feet_s():
    """The node entering after the right foot's touchdown (a double support entered from the left foot's stance) takes
    entering_controls when the horizon's other double support followed the left foot's touchdown; "rollout" takes that
    one's control; a node whose phase the horizon holds takes its latest control in both."""
    keys = [R, R, D, D, L, L, L, D]  # node 7: the right foot lands; nodes 2-3: the left foot landed
    us_last = np.arange(8.0)
    calls = []

    def entering(x, node):
        calls.append(node)
        return np.full(NU, -1.0)

    assert _guess(_mpc(keys, "rollout"), us_last)[7] == 4.0  # node 3, after the shift the old node 4
    assert _guess(_mpc(keys, "phase", entering), us_last)[7] == -1.0
    assert calls == [7]
    keys = [R, R, D, D, L, L, L, L]  # the entering node's single support is in the horizon (nodes 4-6)
    assert _guess(_mpc(keys, "phase", entering), us_last)[7] == 7.0  # node 6 (the old node 7)
    assert calls == [7]


def test_phase_needs_entering_controls():
    with pytest.raises(ParameterError, match="horizon_end='phase' needs entering_controls"):
        _mpc([L, R], "phase")
