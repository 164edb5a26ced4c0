"""SequencerParams: presets, TOML loading, validation messages."""

import dataclasses
import math

import pytest

from sequencer import SequencerParams
from wbmpc.errors import ParameterError


def test_table_i_preset_matches_the_paper():
    p = SequencerParams.table_i()
    assert (p.alpha1, p.alpha2, p.alpha3) == (1e3, 1.0, 1e6)
    assert p.z_c == 0.31
    assert (p.l_min, p.l_nom, p.l_max) == pytest.approx((-0.3, 0.1, 0.3))
    assert (p.w_left_min, p.w_nom("left"), p.w_left_max) == pytest.approx((-0.40, -0.25, -0.10))
    assert (p.w_right_min, p.w_nom("right"), p.w_right_max) == pytest.approx((0.10, 0.25, 0.40))
    assert (p.t_min, p.t_nom, p.t_max) == (0.1, 0.3, 1.0)
    assert p.omega == pytest.approx(math.sqrt(9.81 / 0.31))
    assert p.v_x == pytest.approx(0.1 / 0.3)


def test_bolt_preset_is_narrower_than_table_i_and_uses_bolt_com_height():
    bolt, table = SequencerParams.bolt_walking(), SequencerParams.table_i()
    assert abs(bolt.w_nom("left")) < abs(table.w_nom("left"))
    assert bolt.w_right_min < table.w_right_min
    # z_c is the CoM height of the robot description's standing pose (feet on the floor).
    import pinocchio as pin

    from robots import load_robot

    robot = load_robot("bolt")
    model = robot.pinocchio_model
    com_height = pin.centerOfMass(model, model.createData(), robot.q_reference)[2]
    assert bolt.z_c == pytest.approx(com_height, abs=1e-3)


def test_replace_revalidates_and_converts_to_float():
    p = dataclasses.replace(SequencerParams.table_i(), v_x=0, horizon=2)
    assert p.l_nom == 0.0 and isinstance(p.horizon, float)
    with pytest.raises(ParameterError, match=r"z_c=-0.1 must be > 0"):
        dataclasses.replace(p, z_c=-0.1)


@pytest.mark.parametrize(
    "change, message",
    [
        ({"l_min": 0.4}, r"l_min=0.4 m must be <= l_max=0.3 m"),
        ({"w_right_min": 0.5}, r"w_right_min=0.5 m must be <= w_right_max=0.4 m"),
        ({"z_c": 0.0}, r"z_c=0.0 must be > 0"),
        ({"t_min": 0.0}, r"t_min=0.0 s must be > 0"),
        ({"t_min": 0.5}, r"0 < t_min <= t_nom <= t_max, got t_min=0.5 s, t_nom=0.3 s"),
        ({"alpha3": float("nan")}, r"alpha3=nan must be finite"),
        ({"horizon": float("inf")}, r"horizon=inf must be finite"),
        ({"v_x": 2.0}, r"v_x=2.0 m/s gives a nominal step length .* outside \[l_min, l_max\]"),
        ({"pelvis_width": 0.5}, r"pelvis_width=0.5 m .* nominal left-stance width -0.5 m outside"),
        ({"alpha1": "big"}, r"alpha1='big' must be a real number"),
    ],
)
def test_bad_parameters_raise_with_field_value_and_range(change, message):
    with pytest.raises(ParameterError, match=message):
        dataclasses.replace(SequencerParams.table_i(), **change)


def test_toml_round_trip_and_errors(tmp_path):
    path = tmp_path / "p.toml"
    path.write_text("z_c = 0.28\nv_x = 0.2\n")
    p = SequencerParams.from_toml(path)
    assert p.z_c == 0.28 and p.v_x == 0.2 and p.alpha3 == 1e6
    path.write_text("zc = 0.28\n")
    with pytest.raises(ParameterError, match=r"unknown sequencer parameter\(s\) \['zc'\]"):
        SequencerParams.from_toml(path)
    with pytest.raises(ParameterError, match="does not exist"):
        SequencerParams.from_toml(tmp_path / "missing.toml")
    with pytest.raises(ParameterError, match=r"preset='walk' is not known \(available: \['bolt_walking', 'table_i'\]\)"):
        SequencerParams.preset("walk")


@pytest.mark.parametrize("preset", ["table_i", "bolt_walking"])
def test_nominal_gait_of_the_own_values_is_l_nom_w_nom_b_nom_bit_for_bit(preset):
    p = dataclasses.replace(SequencerParams.preset(preset), v_y=0.05, swing_drift=0.2, dcm_offset_bias=0.01)
    gait = p.nominal_gait()
    assert gait.step_length == p.l_nom
    for foot in ("left", "right"):
        assert gait.step_width(foot) == p.w_nom(foot)
        assert gait.dcm_offset(foot) == p.b_nom(foot)
    other = p.nominal_gait(v_x=0.2, v_y=0.0, swing_drift=0.0, dcm_offset_bias=0.0)
    rebuilt = dataclasses.replace(p, v_x=0.2, v_y=0.0, swing_drift=0.0, dcm_offset_bias=0.0)
    assert other.step_length == rebuilt.l_nom and other.dcm_offset("right") == rebuilt.b_nom("right")
    with pytest.raises(ParameterError, match=r"swing_drift=1.0 must be in \[0, 0.9\]"):
        p.nominal_gait(swing_drift=1.0)
    with pytest.raises(ParameterError, match=r"v_x=-2.0 m/s .* v_x must lie within"):
        p.nominal_gait(v_x=-2.0)


def test_velocity_range_and_the_commands_it_admits():
    p = SequencerParams.table_i()
    assert p.velocity_range() == {"v_x": pytest.approx((-1.0, 1.0)), "v_y": pytest.approx((-0.5, 0.5))}
    low, high = p.velocity_range()["v_x"]
    p.check_velocity(low, 0.0)
    p.check_velocity(high, 0.0)
    with pytest.raises(ParameterError, match=r"v_x=1.01 m/s gives a nominal step length"):
        p.check_velocity(1.01, 0.0)
    with pytest.raises(ParameterError, match=r"v_y=0.51 m/s give a nominal left-stance width -0.097 m outside "
                                             r"\[w_left_min, w_left_max\] = \[-0.4, -0.1\] m"):
        p.check_velocity(0.0, 0.51)
