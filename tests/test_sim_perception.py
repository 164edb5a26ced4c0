"""Rangefinder perception (sim.perception): the configuration, the array's geometry, the height map, and
the estimate against the true scene on random box layouts (the H1's rangefinders in MuJoCo, the robot
moved kinematically toward the boxes: no controller, so the figures are the perception's own)."""

from __future__ import annotations

import dataclasses
import tomllib

import mujoco
import numpy as np
import pytest
from robot_extras import needs_h1_extra

from robots.conventions import pinocchio_to_mujoco_state
from sequencer.obstacles import Obstacle
from sim.perception import HeightMap, PerceptionPipeline, quaternion_z_to, ray_directions_base
from sim.perception.terrain import NEAR_EDGE_MAX_CORRECTION, near_edge_yaw
from wbmpc.errors import ParameterError
from wbmpc.walking.perception_config import PerceptionConfig
from wbmpc.walking.preset import PRESET_DIR, load_walking_preset

SCAN_DT = 0.015  # [s] between scans (67 Hz)
WALK_SPEED = 0.5  # [m/s] of the kinematic approach


# ---------------------------------------------------------------------------------------- configuration


def test_h1_preset_states_every_perception_field_and_the_others_have_none():
    with (PRESET_DIR / "h1.toml").open("rb") as stream:
        stated = set(tomllib.load(stream)["perception"])
    assert {f.name for f in dataclasses.fields(PerceptionConfig)} <= stated
    h1 = load_walking_preset("h1").perception
    assert h1.enabled and h1.n_rays == len(h1.pitch_deg) * len(h1.yaw_deg) == 119 and h1.rate == 67.0
    assert load_walking_preset("bolt").perception is None  # no [perception]: Measurement.obstacles stays ()
    noisy = load_walking_preset("bolt", {"perception.noise_std": 0.01}).perception  # an override turns it on
    assert noisy.noise_std == 0.01 and noisy.enabled
    assert load_walking_preset("h1", {"perception.enabled": False}).perception.enabled is False


@pytest.mark.parametrize(("override", "message"), [
    ({"rate": 0.0}, r"perception.rate=0.0 Hz must be in \(0.0, 1000.0\] Hz"),
    ({"pitch_deg": [10.0, 95.0]}, r"perception.pitch_deg=.* must be a non-empty list of angles in \[0.0, 90.0\] deg"),
    ({"dropout_probability": 1.5}, r"perception.dropout_probability=1.5 - must be in \[0.0, 1.0\]"),
    ({"blackouts": [[2.0, 1.0]]}, r"perception.blackouts: \[2.0, 1.0\] must be finite times with 0 <= start < end"),
    ({"mount_position": [0.1, 0.0]}, r"perception.mount_position=.* must be 3 finite numbers"),
    ({"min_returns": 0}, r"perception.min_returns=0 must be an integer >= 1"),
    ({"min_ground_distance": 5.0}, r"perception.min_ground_distance=5.0 m must be below max_range=4.0 m"),
    ({"obstacle_axis": "box"}, r"perception.obstacle_axis='box' must be one of \('heading', 'near_edge'\)"),
])
def test_bad_perception_values_are_refused_in_one_line(override, message):
    key, value = next(iter(override.items()))
    with pytest.raises(ParameterError, match=message) as error:
        load_walking_preset("h1", {f"perception.{key}": value})
    assert "\n" not in str(error.value)
    with pytest.raises(ParameterError, match=r"\[perception\] has no field \['ratez'\]"):
        load_walking_preset("h1", {"perception.ratez": 3.0})


def test_each_site_looks_along_its_ray():
    config = PerceptionConfig()
    directions = ray_directions_base(config.ray_angles_deg())
    assert directions.shape == (config.n_rays, 3)
    np.testing.assert_allclose(np.linalg.norm(directions, axis=1), 1.0)
    pitch, yaw = np.deg2rad(config.ray_angles_deg()[-1])  # the last ray: 60 deg down, 15 deg left
    np.testing.assert_allclose(directions[-1], [np.cos(pitch) * np.cos(yaw), np.cos(pitch) * np.sin(yaw), -np.sin(pitch)])
    for direction in [*directions, [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]:
        rotation = np.zeros(9)
        mujoco.mju_quat2Mat(rotation, quaternion_z_to(direction))
        np.testing.assert_allclose(rotation.reshape(3, 3)[:, 2], direction, atol=1e-12)


def test_height_map_keeps_cell_statistics_and_the_bounds_of_high_returns():
    grid = HeightMap(0.1)
    grid.add(np.array([[0.01, 0.01, 0.0], [0.05, 0.02, 0.2], [0.31, 0.0, 0.1]]), high_above=0.1)
    grid.add(np.array([[0.09, 0.08, 0.4]]), high_above=0.1)
    assert grid.n_cells == 2 and grid.count.tolist() == [3, 1]
    np.testing.assert_allclose(grid.height, [0.2, 0.1])
    np.testing.assert_allclose(grid.bounds[0], [0.01, 0.09, 0.01, 0.08])
    np.testing.assert_allclose(grid.high_bounds[0], [0.05, 0.09, 0.02, 0.08])  # the ground return left out
    assert np.all(np.isinf(grid.high_bounds[1]))  # 0.1 is not above 0.1
    np.testing.assert_allclose(grid.height_at([[0.05, 0.05], [0.35, 0.05], [5.0, 5.0]]), [0.2, 0.1, np.nan])
    np.testing.assert_allclose(grid.profile([0.05, 0.05], 0.0, [0.0, 0.3, 0.1]), [0.2, 0.1, np.nan])
    many = HeightMap(0.01)
    many.add(np.column_stack([np.arange(3000) * 0.01 + 0.005, np.zeros(3000), np.ones(3000)]))  # grows its buffers
    assert many.n_cells == 3000 and np.all(many.height == 1.0)


def test_height_map_equals_a_return_by_return_reference_on_random_scans():
    """Scans of random returns (negative cell indices included), accumulated: every cell's row, count, mean,
    bounds and high bounds equal those of a dict kept return by return, the rows in the order the cells were first
    seen (within a scan by (ix, iy)); ``rows_near`` and ``height_at`` equal their brute-force answers."""
    rng = np.random.default_rng(3)
    grid, cell = HeightMap(0.02), 0.02
    reference: dict[tuple[int, int], dict] = {}
    for scan in range(40):
        points = np.column_stack([rng.uniform(-1.0, 1.0, 150) + 0.05 * scan, rng.uniform(-0.6, 0.6, 150),
                                  rng.choice([0.0, 0.1, 0.3], 150) + rng.normal(0.0, 0.01, 150)])
        grid.add(points, high_above=0.05)
        keys = [(int(np.floor(x / cell)), int(np.floor(y / cell))) for x, y in points[:, :2]]
        for key in sorted(set(keys) - set(reference)):
            reference[key] = {"row": len(reference), "z": [], "xy": [], "high": []}
        for key, point in zip(keys, points):
            reference[key]["z"].append(point[2])
            reference[key]["xy"].append(point[:2])
            if point[2] > 0.05:
                reference[key]["high"].append(point[:2])
    assert grid.n_cells == len(reference)
    for key, cell_data in reference.items():
        row = cell_data["row"]
        assert tuple(grid.keys[row]) == key and grid.count[row] == len(cell_data["z"])
        np.testing.assert_allclose(grid.height[row], np.mean(cell_data["z"]), rtol=0, atol=1e-15)
        xy = np.array(cell_data["xy"])
        assert grid.bounds[row].tolist() == [xy[:, 0].min(), xy[:, 0].max(), xy[:, 1].min(), xy[:, 1].max()]
        high = np.array(cell_data["high"]).reshape(-1, 2)
        expected = ([high[:, 0].min(), high[:, 0].max(), high[:, 1].min(), high[:, 1].max()] if len(high)
                    else [np.inf, -np.inf, np.inf, -np.inf])
        assert grid.high_bounds[row].tolist() == expected
        assert grid.centers()[row].tolist() == [(key[0] + 0.5) * cell, (key[1] + 0.5) * cell]
    for center in ([0.3, 0.1], [-0.9, 0.5], [5.0, 5.0]):
        brute = np.flatnonzero(np.hypot(*(grid.centers() - center).T) <= 0.4)
        assert grid.rows_near(center, 0.4).tolist() == brute.tolist()
    queries = rng.uniform(-1.5, 3.5, (200, 2))
    expected = [grid.height[reference[key]["row"]] if (key := (int(np.floor(x / cell)), int(np.floor(y / cell))))
                in reference else np.nan for x, y in queries]
    np.testing.assert_array_equal(grid.height_at(queries), expected)
    assert np.isnan(HeightMap(0.02).height_at([[0.0, 0.0]])).all()


# ---------------------------------------------------------------------------------------- against the scene


@pytest.fixture(scope="module")
def h1():
    from robots import load_robot

    return load_robot("h1")


def scene(h1, config, boxes, perceivable=True):
    """The H1's MuJoCo model with ``config``'s rangefinders and ``boxes`` (rows: near edge x, depth,
    width, height, lateral offset [m], and optionally the yaw [rad] of the box about its centre, which is
    at (near edge x + depth / 2, lateral offset) whatever the yaw); returns (model, data)."""
    from robots.mujoco_model import add_box_geom, build_mujoco_spec

    spec = build_mujoco_spec(h1, link_collisions=True)
    PerceptionPipeline.add_to_spec(spec, config, h1.base_body)
    for k, box in enumerate(boxes):
        near, depth, width, height, offset = box[:5]
        add_box_geom(spec, f"obstacle_{k}", np.array([near + 0.5 * depth, offset, 0.5 * height]),
                     0.5 * np.array([depth, width, height]), yaw=box[5] if len(box) > 5 else 0.0,
                     rgba=(0.8, 0.4, 0.2, 1.0 if perceivable else 0.0))
    model = spec.compile()
    return model, mujoco.MjData(model)


def approach(h1, model, data, config, stop_x, seed=0, q=None):
    """Scan every SCAN_DT while the standing H1 slides along x at WALK_SPEED up to base x = ``stop_x``;
    returns the pipeline and the base x of its scans."""
    pipeline = PerceptionPipeline(model, config, seed, h1)
    q = np.array(h1.q_reference if q is None else q, dtype=float)
    xs = np.arange(0.0, stop_x + 1e-9, WALK_SPEED * SCAN_DT)
    for k, x in enumerate(xs):
        q[0] = x
        data.qpos[:], _ = pinocchio_to_mujoco_state(h1, q, np.zeros(h1.nv))
        pipeline.step(0, k * SCAN_DT, model, data, np.concatenate([q, np.zeros(h1.nv)]))
    return pipeline, xs


def random_layout(rng):
    """One box across the path: near edge 1.8-2.8 m ahead, depth 0.1-0.3 m, width 0.8-1.5 m, height
    0.1-0.4 m, centre 0-0.1 m off the path."""
    return np.array([[rng.uniform(1.8, 2.8), rng.uniform(0.1, 0.3), rng.uniform(0.8, 1.5), rng.uniform(0.1, 0.4),
                      rng.uniform(-0.1, 0.1)]])


def estimate_errors(pipeline, box):
    """(height, near edge, far edge) errors of the reported obstacle [m], estimate minus truth."""
    (obstacle,) = pipeline.estimator.obstacles
    near, depth, _, height, _ = box
    along = obstacle.center[0], 0.5 * obstacle.depth
    return obstacle.height - height, along[0] - along[1] - near, along[0] + along[1] - (near + depth)


def yawed_layout(rng):
    """A box of :func:`random_layout` yawed about its centre by up to 0.3 rad either way (its row with the
    yaw appended), and a robot heading up to 0.05 rad (3 deg) either way off the path (x) [rad]."""
    return np.append(random_layout(rng)[0], rng.uniform(-0.3, 0.3)), rng.uniform(-0.05, 0.05)


def turned(h1, heading):
    """The H1's reference configuration turned to ``heading`` [rad] about z (world frame)."""
    q = np.array(h1.q_reference, dtype=float)
    q[3:7] = [0.0, 0.0, np.sin(0.5 * heading), np.cos(0.5 * heading)]  # Pinocchio's (x, y, z, w)
    return q


def axis_errors(obstacle, box):
    """(yaw [rad], depth, near edge, far edge [m]) errors of ``obstacle`` against ``box`` (a :func:`scene`
    row with its yaw), estimate minus truth; the edges are where the line through the box's centre along
    its own depth axis enters and leaves the reported footprint (< 0: toward the robot)."""
    near, depth, width, height, offset, yaw = box
    truth = Obstacle(center=[near + 0.5 * depth, offset], yaw=yaw, depth=depth, width=width, height=height)
    entry, exit_ = obstacle.interval_along(truth.center - truth.axes[0], yaw)  # from 1 m before the centre
    return obstacle.yaw - yaw, obstacle.depth - depth, entry - (1.0 - 0.5 * depth), exit_ - (1.0 + 0.5 * depth)


def axis_estimates(h1, config, box, heading, seed=0):
    """The obstacle reported by each of the two ``obstacle_axis`` options (``config``'s other fields) once
    the H1, heading ``heading`` [rad], has slid along x until ``box``'s near edge is 1 m ahead."""
    estimates = {}
    for axis in ("heading", "near_edge"):
        option = dataclasses.replace(config, obstacle_axis=axis)
        model, data = scene(h1, option, [box])
        pipeline, _ = approach(h1, model, data, option, stop_x=box[0] - 1.0, seed=seed, q=turned(h1, heading))
        (estimates[axis],) = pipeline.estimator.obstacles
    return estimates


@needs_h1_extra
def test_a_box_is_reported_within_1_cm_at_1_m_without_noise_on_random_layouts(h1):
    """Issue 15's target: the height estimate within 1 cm on the top at 1 m without noise; measured
    (docs/perception.md) on 6 layouts: height within 0.6 mm, near edge 0.5 mm, far edge 0.5 mm."""
    config = load_walking_preset("h1").perception
    rng = np.random.default_rng(15)
    for _ in range(6):
        box = random_layout(rng)[0]
        model, data = scene(h1, config, [box])
        pipeline, xs = approach(h1, model, data, config, stop_x=box[0] - 1.0)  # the near edge 1 m ahead
        height_error, near_error, far_error = estimate_errors(pipeline, box)
        assert abs(height_error) <= 0.01 and abs(height_error) < 2e-3
        assert abs(near_error) < 3e-3 and abs(far_error) < 0.01
        track = pipeline.estimator.tracks[0]
        first = xs[int(round(track.first_seen / SCAN_DT))]
        assert box[0] - first > 2.0 or first < 0.05  # first reported more than 2 m ahead, or at once when nearer
        assert abs(track.obstacle.center[1] - box[4]) < 0.05  # the fan's lateral extent, centred on the path


@needs_h1_extra
def test_the_near_edge_axis_sizes_a_yawed_box_within_1_cm_at_1_m_and_the_heading_axis_does_not(h1):
    """Boxes yawed up to 0.3 rad, the robot heading up to 0.05 rad off the path, no noise, the near edge 1 m
    ahead. Measured on these 6 layouts with the near edge's normal: yaw within 1.2 mrad, depth +1.2..+9.0 mm
    (the cells' world-aligned bounds make a yawed box look up to ~6 mm larger per edge at 0.3 rad), near edge
    -5.2..-1.2 mm, far edge -1.0..+3.8 mm; with the heading: yaw off by the whole angle (0.03-0.30 rad), the
    box 25-220 mm deeper (docs/perception.md, "The obstacle's depth axis")."""
    config = load_walking_preset("h1").perception
    rng = np.random.default_rng(17)
    errors, headings, yaws = {"heading": [], "near_edge": []}, [], []
    for _ in range(6):
        box, heading = yawed_layout(rng)
        for axis, obstacle in axis_estimates(h1, config, box, heading).items():
            errors[axis].append(axis_errors(obstacle, box))
        headings.append(heading)
        yaws.append(box[5])
    fitted, along_heading = np.array(errors["near_edge"]), np.array(errors["heading"])
    yaw_error, depth_error, near_error, far_error = fitted.T
    assert np.all(np.abs(yaw_error) < 3e-3) and np.all(np.abs(depth_error) < 0.01)
    assert np.all((-8e-3 < near_error) & (near_error < 1e-3)) and np.all((-2e-3 < far_error) & (far_error < 6e-3))
    # the heading's axis: the heading at the first report, whatever the box
    np.testing.assert_allclose(along_heading[:, 0], np.subtract(headings, yaws), atol=1e-12)
    assert np.abs(along_heading[:, 0]).mean() > 30 * np.abs(yaw_error).mean()
    assert np.abs(along_heading[:, 1]).max() > 0.1 and np.all(along_heading[:, 1] > depth_error - 1e-3)


@needs_h1_extra
def test_a_box_across_the_path_gets_the_same_obstacle_from_both_axes(h1):
    """The box across the path and the robot heading exactly along it, no noise: the near edge's fit agrees
    with the heading to 1 urad and 1 um (measured: the same obstacle, to the last bit)."""
    config = load_walking_preset("h1").perception
    rng = np.random.default_rng(18)
    for _ in range(3):
        box = np.append(random_layout(rng)[0], 0.0)
        estimates = axis_estimates(h1, config, box, heading=0.0)
        along_heading, fitted = estimates["heading"], estimates["near_edge"]
        assert along_heading.yaw == 0.0 and abs(fitted.yaw) < 1e-6
        assert abs(fitted.depth - along_heading.depth) < 1e-6 and abs(fitted.width - along_heading.width) < 1e-6
        np.testing.assert_allclose(fitted.center, along_heading.center, atol=1e-6)


@needs_h1_extra
def test_with_range_noise_the_near_edge_axis_still_reports_a_yawed_box_within_its_measured_bounds(h1):
    """5 mm range noise (seeded) on yawed boxes (as above), the near edge's normal: the box is reported, its
    edges pushed outward by the noise as with the heading's axis. Measured on these 4 layouts: yaw within
    2.8 mrad, depth +16..+22 mm, near edge -17..-12 mm, far edge +3..+6 mm, height within 0.5 mm."""
    config = dataclasses.replace(load_walking_preset("h1").perception, noise_std=0.005, obstacle_axis="near_edge")
    rng = np.random.default_rng(19)
    for seed in range(4):
        box, heading = yawed_layout(rng)
        model, data = scene(h1, config, [box])
        pipeline, _ = approach(h1, model, data, config, stop_x=box[0] - 1.0, seed=seed, q=turned(h1, heading))
        (obstacle,) = pipeline.estimator.obstacles
        yaw_error, depth_error, near_error, far_error = axis_errors(obstacle, box)
        assert abs(yaw_error) < 6e-3 and 0.0 < depth_error < 0.04
        assert -0.025 < near_error < -0.005 and 0.0 < far_error < 0.015
        assert abs(obstacle.height - box[3]) < 0.01


def test_the_near_edge_fit_finds_a_slanted_edge_and_keeps_the_heading_when_not_trusted():
    """Cells on a box's front face (yaw 0.2 rad, seen from a heading of 0.05 rad) and on its top behind it:
    the fit gives the face's normal; too short an edge, or an edge turned past NEAR_EDGE_MAX_CORRECTION
    from the heading, gives None (the heading is kept)."""
    def cells(yaw, half_width, depth=0.2):
        """2 mm boxes (x_min, x_max, y_min, y_max) [m] on the face through (2, 0) of normal ``yaw`` and on the top."""
        normal, edge = np.array([np.cos(yaw), np.sin(yaw)]), np.array([-np.sin(yaw), np.cos(yaw)])
        across, behind = np.meshgrid(np.arange(-half_width, half_width, 0.02), np.arange(0.0, depth, 0.05))
        points = np.array([2.0, 0.0]) + across.reshape(-1, 1) * edge + behind.reshape(-1, 1) * normal
        return np.column_stack([points[:, 0] - 1e-3, points[:, 0] + 1e-3, points[:, 1] - 1e-3, points[:, 1] + 1e-3])

    bin_width = 0.06
    assert near_edge_yaw(cells(0.2, 0.5), 0.05, bin_width) == pytest.approx(0.2, abs=5e-3)
    assert near_edge_yaw(cells(-0.2, 0.5), 0.05, bin_width) == pytest.approx(-0.2, abs=5e-3)
    assert near_edge_yaw(cells(0.2, 0.1), 0.05, bin_width) is None  # 0.2 m across: too short
    assert near_edge_yaw(cells(0.1 + NEAR_EDGE_MAX_CORRECTION, 0.5), 0.05, bin_width) is None


@pytest.fixture(scope="module")
def g1():
    from robots import load_robot

    return load_robot("g1")


def test_the_g1s_rays_see_the_ground_from_0_51_to_2_20_m_and_report_its_lowest_box(g1):
    """The G1's fan (its preset's [perception], docs/perception.md "The G1's rangefinders"): standing, every ray
    meets the ground 0.12 + 0.757 / tan(p) m ahead of the pelvis, 0.514 m (62.5 deg) to 2.199 m (20 deg), and the
    campaign's lowest box (0.08 m) is reported within 1 cm of its height and near edge with its near edge 1 m ahead."""
    with (PRESET_DIR / "g1.toml").open("rb") as stream:
        stated = set(tomllib.load(stream)["perception"])
    assert {f.name for f in dataclasses.fields(PerceptionConfig)} <= stated
    config = load_walking_preset("g1").perception
    assert config.enabled and config.n_rays == len(config.pitch_deg) * len(config.yaw_deg) == 126
    model, data = scene(g1, config, [])
    pipeline, _ = approach(g1, model, data, config, stop_x=0.0)  # one scan, standing at base x = 0
    q = np.array(g1.q_reference)
    q[0] = 0.0
    points = pipeline.sensor.last.points_world(q[:7])
    assert np.all(np.isfinite(points)) and np.all(np.abs(points[:, 2]) < 1e-3)  # every ray on the ground
    ahead = points[np.abs(points[:, 1]) < 1e-9, 0]  # the rays of yaw 0 (the +-15 deg ones: 0.500-2.128 m along x)
    assert len(ahead) == len(config.pitch_deg)
    assert ahead.min() == pytest.approx(0.514, abs=2e-3) and ahead.max() == pytest.approx(2.199, abs=2e-3)
    assert pipeline.estimator.obstacles == ()
    box = [2.0, 0.15, 1.2, 0.08, 0.0]
    model, data = scene(g1, config, [box])
    pipeline, _ = approach(g1, model, data, config, stop_x=box[0] - 1.0)
    height_error, near_error, far_error = estimate_errors(pipeline, box)
    assert abs(height_error) < 0.01 and abs(near_error) < 0.01


@needs_h1_extra
def test_with_range_noise_the_box_is_still_reported_and_the_errors_stay_within_their_measured_bounds(h1):
    """1 cm range noise (seeded): height within 1 cm, the edges pushed outward (the extremes of noisy
    returns) by at most 5 cm: the reported box is larger, not shorter (docs/perception.md)."""
    config = dataclasses.replace(load_walking_preset("h1").perception, noise_std=0.01)
    rng = np.random.default_rng(16)
    for seed in range(4):
        box = random_layout(rng)[0]
        model, data = scene(h1, config, [box])
        pipeline, _ = approach(h1, model, data, config, stop_x=box[0] - 1.0, seed=seed)
        height_error, near_error, far_error = estimate_errors(pipeline, box)
        assert abs(height_error) < 0.01
        assert -0.05 < near_error < 0.005 and -0.005 < far_error < 0.05


@needs_h1_extra
def test_two_boxes_are_two_obstacles_and_the_nearer_one_stays_known_out_of_view(h1):
    config = load_walking_preset("h1").perception
    boxes = np.array([[1.6, 0.15, 1.2, 0.15, 0.0], [2.9, 0.2, 1.2, 0.3, 0.0]])
    model, data = scene(h1, config, boxes)
    pipeline, _ = approach(h1, model, data, config, stop_x=1.45)  # the first box under the rays' blind zone
    obstacles = sorted(pipeline.estimator.obstacles, key=lambda o: o.center[0])
    assert len(obstacles) == 2
    for obstacle, (near, _depth, _, height, _) in zip(obstacles, boxes):
        assert abs(obstacle.height - height) < 0.01
        assert abs(obstacle.interval_along([0.0, 0.0], 0.0)[0] - near) < 0.01
    assert obstacles[0].interval_along([1.45, 0.0], 0.0)[0] < 0.2  # 0.15 m ahead: seen only from memory


@needs_h1_extra
@pytest.mark.parametrize(("joints", "beyond_min_ground_distance"), [
    ({"left_hip_pitch": -1.2, "left_knee": 1.25, "left_hip_roll": -0.3}, False),  # knee raised, hit 0.41 m ahead
    ({"left_hip_pitch": -1.4, "left_knee": 1.25, "left_hip_roll": -0.3}, True),  # its foot hit 0.62 m ahead
])
def test_the_robots_own_leg_in_the_rays_is_not_an_obstacle(h1, joints, beyond_min_ground_distance):
    """Leg poses the rays hit (found over a grid of poses, docs/perception.md): the returns near the base
    or near the leg (placed by the measured configuration) are dropped. Without both filters the leg
    reads as an obstacle."""
    config = load_walking_preset("h1").perception
    q = np.array(h1.q_reference)
    for name, angle in joints.items():
        q[7 + h1.actuated_joint_names.index(name)] = angle
    model, data = scene(h1, config, [])
    pipeline, _ = approach(h1, model, data, config, stop_x=0.2, q=q)
    assert pipeline.estimator.n_dropped_near > 0 and pipeline.estimator.obstacles == ()
    unfiltered = dataclasses.replace(config, min_ground_distance=0.0, self_filter_radius=0.0)
    model, data = scene(h1, unfiltered, [])
    pipeline, _ = approach(h1, model, data, unfiltered, stop_x=0.2, q=q)
    assert len(pipeline.estimator.obstacles) == 1  # the leg
    distance_only = dataclasses.replace(config, self_filter_radius=0.0)
    model, data = scene(h1, distance_only, [])
    pipeline, _ = approach(h1, model, data, distance_only, stop_x=0.2, q=q)
    assert len(pipeline.estimator.obstacles) == int(beyond_min_ground_distance)  # what the self filter adds


@needs_h1_extra
def test_faults_blackout_dropouts_and_an_unseen_box(h1):
    config = load_walking_preset("h1").perception
    box = [2.2, 0.2, 1.2, 0.2, 0.0]
    # every ray lost after 1.5 s: the box, reported before, stays reported; the scans are empty
    blackout = dataclasses.replace(config, blackouts=((1.5, 100.0),))
    model, data = scene(h1, blackout, [box])
    pipeline, xs = approach(h1, model, data, blackout, stop_x=1.2)
    assert pipeline.n_empty_scans == sum(k * SCAN_DT >= 1.5 for k in range(len(xs))) > 0
    assert len(pipeline.estimator.obstacles) == 1 and pipeline.sensor.last.n_returns == 0
    # every ray lost at every scan: nothing is reported, nothing breaks
    dead = dataclasses.replace(config, dropout_probability=1.0)
    model, data = scene(h1, dead, [box])
    pipeline, _ = approach(h1, model, data, dead, stop_x=1.2)
    assert pipeline.estimator.obstacles == () and pipeline.estimator.ground is None
    # 30 % of the rays lost (seeded): the box is still reported, its height within 1 cm
    lossy = dataclasses.replace(config, dropout_probability=0.3)
    model, data = scene(h1, lossy, [box])
    pipeline, _ = approach(h1, model, data, lossy, stop_x=1.2)
    assert len(pipeline.estimator.obstacles) == 1 and abs(pipeline.estimator.obstacles[0].height - 0.2) < 0.01
    # a box the rays do not see (alpha 0): a missed detection
    model, data = scene(h1, config, [box], perceivable=False)
    pipeline, _ = approach(h1, model, data, config, stop_x=1.2)
    assert pipeline.estimator.obstacles == ()


@needs_h1_extra
def test_the_array_scans_at_its_rate_and_with_sensors_off_between_scans(h1):
    config = load_walking_preset("h1").perception
    model, data = scene(h1, config, [])
    pipeline = PerceptionPipeline(model, config, seed=0)
    assert pipeline.sensor.period_ticks == 15 and pipeline.sensor.rate == pytest.approx(66.67, abs=0.01)
    assert model.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_SENSOR)  # mj_step computes no ray
    x = np.concatenate([h1.q_reference, np.zeros(h1.nv)])
    data.qpos[:], _ = pinocchio_to_mujoco_state(h1, h1.q_reference, np.zeros(h1.nv))
    for tick in range(46):
        pipeline.step(tick, tick * 1e-3, model, data, x)
    assert pipeline.sensor.n_scans == 4  # ticks 0, 15, 30, 45
    scan = pipeline.sensor.last
    assert scan.n_returns == config.n_rays and scan.t == pytest.approx(0.045)
    np.testing.assert_allclose(scan.points_world(x)[:, 2], 0.0, atol=1e-9)  # the floor
