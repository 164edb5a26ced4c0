"""The planner interface's inputs: VelocityCommand, StanceState, ReducedState (validation, conversions)."""

import numpy as np
import pytest

from sequencer import ReducedState, StanceState, VelocityCommand
from wbmpc.errors import ParameterError


def test_velocity_command_from_tuples_and_back():
    assert VelocityCommand.from_tuple((0.3,)) == VelocityCommand(0.3, 0.0, 0.0)
    assert VelocityCommand.from_tuple([0.3, -0.1, 0.2]).as_tuple() == (0.3, -0.1, 0.2)
    command = VelocityCommand(0.1)
    assert VelocityCommand.from_tuple(command) is command
    assert isinstance(VelocityCommand(np.float32(0.5)).v_x, float)
    with pytest.raises(ParameterError, match=r"velocity_command=\(1, 2, 3, 4\) must be \(v_x, v_y, yaw_rate\)"):
        VelocityCommand.from_tuple((1, 2, 3, 4))
    with pytest.raises(ParameterError, match=r"velocity_command='fast' must be"):
        VelocityCommand.from_tuple("fast")
    with pytest.raises(ParameterError, match=r"yaw_rate=nan must be finite"):
        VelocityCommand(0.1, 0.0, float("nan"))
    with pytest.raises(ParameterError, match=r"v_x=True must be a real number"):
        VelocityCommand(True)


def test_stance_and_reduced_state_are_validated_and_read_only():
    stance = StanceState("left", [0.1, 0.2], 0.5, 1.0)
    assert stance.position.shape == (2,) and not stance.position.flags.writeable
    with pytest.raises(ParameterError, match=r"stance position=\[0.1, 0.2, 0.3\] must be 2 finite numbers"):
        StanceState("left", [0.1, 0.2, 0.3], 0.0, 0.0)
    with pytest.raises(ParameterError, match=r"stance position='here' must be 2 finite numbers"):
        StanceState("left", "here", 0.0, 0.0)
    with pytest.raises(ParameterError, match=r"stance yaw=inf must be finite"):
        StanceState("left", [0.0, 0.0], float("inf"), 0.0)
    state = ReducedState([0, 0, 0.3], [0.1, 0, 0], [0.02, 0.0])
    assert state.angular_momentum is None and state.dcm.tolist() == [0.02, 0.0]
    with pytest.raises(ParameterError, match=r"dcm=.* must be 2 finite numbers"):
        ReducedState([0, 0, 0.3], [0, 0, 0], [np.nan, 0.0])
    with pytest.raises(ParameterError, match=r"angular_momentum=\[0, 0\] must be 3 finite numbers"):
        ReducedState([0, 0, 0.3], [0, 0, 0], [0, 0], angular_momentum=[0, 0])
