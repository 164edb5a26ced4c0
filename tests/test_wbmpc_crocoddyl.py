"""wbmpc against the Crocoddyl oracle on the same problems: nodes, solves, receding horizon, G1."""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
import pytest

crocoddyl = pytest.importorskip("crocoddyl", reason="Crocoddyl (test extra) is the oracle of these comparisons")

from robot_extras import needs_h1_extra  # noqa: E402
from wbmpc_fixtures import alternating_schedule, random_state, standing_state  # noqa: E402

from bench.crocoddyl_mirror import CrocoddylMirror  # noqa: E402
from robots import load_robot  # noqa: E402
from wbmpc.ocp.solvers import SolverFDDP  # noqa: E402
from wbmpc.walking.mpc import WalkingMPC  # noqa: E402
from wbmpc.walking.ocp import WalkingOCP, WalkingOCPConfig, quasi_static_controls  # noqa: E402
from wbmpc.walking.preset import load_walking_preset  # noqa: E402

pytestmark = pytest.mark.crocoddyl
ALL_TERMS = WalkingOCPConfig(foothold_weight=100.0, contact_force_weight=1e-2, friction_cone_weight=10.0,
                             touchdown_height_weight=1e5, touchdown_velocity_weight=1e3,
                             baumgarte_gains=(20.0, 40.0), evaluation="nodes")  # the node models themselves


def _rel(actual, expected) -> float:
    actual, expected = np.asarray(actual, dtype=float), np.asarray(expected, dtype=float)
    return float(np.max(np.abs(actual - expected)) / max(1e-12, np.max(np.abs(expected))))


@pytest.fixture(scope="module")
def bolt():
    return load_robot("bolt")


def _walking_ocp(robot, config, n_nodes, t0=0.0):
    ocp = WalkingOCP(robot, config, n_nodes=n_nodes, dt=0.01)
    ocp.update(standing_state(robot), alternating_schedule(t0, 0.01, n_nodes), np.array([0.1, 0.0, 0.3]))
    return ocp


@pytest.mark.parametrize("backend", ["pinocchio", "kkt"])
def test_every_node_matches_crocoddyl(bolt, backend):
    """xnext, cost, Fx, Fu, Lx, Lu, Lxx, Luu, Lxu at random states agree to 1e-9 relative."""
    ocp = _walking_ocp(bolt, dataclasses.replace(ALL_TERMS, dynamics_backend=backend), n_nodes=20, t0=0.15)
    mirror = CrocoddylMirror(ocp.problem)
    rng = np.random.default_rng(0)
    xs = [random_state(bolt, rng) for _ in range(21)]
    us = [0.5 * rng.standard_normal(6) for _ in range(20)]
    problem, twin = ocp.problem, mirror.problem
    assert problem.calc(xs, us) == pytest.approx(twin.calc(xs, us), rel=1e-12)
    problem.calcDiff(xs, us)
    twin.calcDiff(xs, us)
    for k in range(21):
        ours = problem.running_datas[k] if k < 20 else problem.terminal_data
        theirs = twin.runningDatas[k] if k < 20 else twin.terminalData
        names = ["xnext", "cost", "Fx", "Lx", "Lxx"] + (["Fu", "Lu", "Luu", "Lxu"] if k < 20 else [])
        for name in names:
            assert _rel(getattr(ours, name), getattr(theirs, name)) < 1e-9, f"node {k} {name}"


def _solve_both(ocp, mirror, maxiter):
    x0 = ocp.problem.x0
    u0 = quasi_static_controls(ocp, x0)
    N = ocp.problem.T
    xs0, us0 = [x0] * (N + 1), [u0] * N
    ours, theirs = SolverFDDP(ocp.problem), crocoddyl.SolverFDDP(mirror.problem)
    return ours, theirs, ours.solve(xs0, us0, maxiter), theirs.solve(xs0, us0, maxiter)


def test_full_solve_matches_crocoddyl(bolt):
    """Same iterations, cost (1e-9 relative), xs/us (1e-6) and gains (opposite sign)."""
    ocp = _walking_ocp(bolt, WalkingOCPConfig(), n_nodes=40)
    mirror = CrocoddylMirror(ocp.problem)
    ours, theirs, ok_ours, ok_theirs = _solve_both(ocp, mirror, maxiter=50)
    assert ok_ours == ok_theirs
    assert ours.iter == theirs.iter
    assert ours.cost == pytest.approx(theirs.cost, rel=1e-9)
    np.testing.assert_allclose(ours.xs, np.array(theirs.xs), atol=1e-6)
    np.testing.assert_allclose(ours.us, np.array(theirs.us), atol=1e-6)
    np.testing.assert_allclose(ours.K, -np.array(theirs.K), atol=1e-4 * np.max(np.abs(theirs.K)))
    assert [entry.step_length for entry in ours.log][:20] == pytest.approx(
        [entry for entry in _crocoddyl_steps(ocp, mirror, 20)])


def _crocoddyl_steps(ocp, mirror, maxiter):
    """Accepted step length of every Crocoddyl iteration (through a callback)."""
    steps = []

    class Steps(crocoddyl.CallbackAbstract):
        def __call__(self, solver):
            steps.append(solver.stepLength)

    x0 = ocp.problem.x0
    u0 = quasi_static_controls(ocp, x0)
    N = ocp.problem.T
    solver = crocoddyl.SolverFDDP(mirror.problem)
    solver.setCallbacks([Steps()])
    solver.solve([x0] * (N + 1), [u0] * N, maxiter)
    return steps


def test_receding_horizon_applies_the_same_controls(bolt):
    """100 MPC ticks (1 iteration each, warm-started by shifting) give Crocoddyl's controls (the
    twin starts from our warm start: the shifted plan with the horizon end rolled out). Ours
    prepares each next update's derivatives ahead (WalkingMPC.prepare), as the closed loop does."""
    n_nodes, dt = 50, 0.01
    mpc = WalkingMPC(bolt, WalkingOCPConfig(), n_nodes=n_nodes, dt=dt, max_iterations=1, cold_start_iterations=10,
                     horizon_end="rollout")
    mirror = CrocoddylMirror(mpc.problem)
    twin = crocoddyl.SolverFDDP(mirror.problem)
    x = standing_state(bolt)
    rng = np.random.default_rng(5)
    worst = 0.0
    used = []
    for tick in range(100):
        t = tick * dt
        schedule = alternating_schedule(t, dt, n_nodes)
        com_ref = np.array([0.1 + 0.3 * t, 0.0, 0.3])
        if tick > 0:  # the guess our update is about to make
            mpc.ocp.update(x, schedule, com_ref)
            guess_xs, guess_us, _ = mpc.warm_start(t, x)
        solution = mpc.update(t, x, schedule, com_ref)
        assert solution.ok, solution.status
        used.append(mpc.problem.prepared_used)
        mirror.update()
        if tick == 0:
            xs0 = [x] * (n_nodes + 1)
            us0 = [quasi_static_controls(mpc.ocp, x)] * n_nodes
            iterations = 10
        else:
            xs0, us0 = list(guess_xs), list(guess_us)
            iterations = 1
        twin.solve(xs0, us0, iterations)
        worst = max(worst, float(np.max(np.abs(solution.us[:2] - np.array(twin.us[:2])))))
        np.testing.assert_allclose(solution.K[1], -np.array(twin.K[1]), atol=1e-5 * np.max(np.abs(twin.K[1])))
        # the "plant": the predicted next state with a small disturbance
        x = solution.xs[1].copy()
        x[mpc.ocp.state.nq:] += 0.01 * rng.standard_normal(mpc.ocp.state.nv)
        mpc.prepare()
    assert worst < 1e-6
    assert np.median(used[1:]) >= n_nodes - 2  # the prepared derivatives were used


def test_closed_loop_with_crocoddyl_as_the_solver_applies_the_same_torques():
    """The whole closed loop (sequencer, MPC, 1 kHz feedback, MuJoCo) with Crocoddyl's FDDP as the
    MPC solver (bench.crocoddyl_loop, the baseline of `wbmpc bench loop`) applies our torques."""
    from bench.crocoddyl_loop import CrocoddylWalkingController
    from sim.runner import run_scenario

    ours = run_scenario("walk", duration=0.4, seed=0, progress=False)
    controller = CrocoddylWalkingController()
    theirs = run_scenario("walk", duration=0.4, seed=0, progress=False, controller=controller)
    assert ours.status == theirs.status == "completed"
    np.testing.assert_allclose(theirs.ticks["tau"], ours.ticks["tau"], rtol=0, atol=1e-6)
    assert controller.mirror_seconds > 0.0


@pytest.mark.parametrize("backend", ["pinocchio", "kkt"])
def test_g1_flat_feet_solve_matches_crocoddyl(backend):
    g1 = load_robot("g1")
    preset = load_walking_preset("g1").ocp  # its flat-foot terms: wrench cones, swing orientation, posture weights
    config = dataclasses.replace(preset, contact_force_weight=1e-4, baumgarte_gains=(10.0, 30.0),
                                 dynamics_backend=backend, evaluation="nodes")
    ocp = WalkingOCP(g1, config, n_nodes=10, dt=0.02)
    x0 = standing_state(g1)
    schedule = alternating_schedule(0.0, 0.02, 10, step_duration=0.4, foot_y=(0.12, -0.12))
    ocp.update(x0, schedule, np.array([0.05, 0.0, 0.7]))
    terms = ocp.problem.running_models[3].differential.costs.costs
    assert terms["left_wrench_cone"].active and terms["right_orientation"].active
    mirror = CrocoddylMirror(ocp.problem)
    rng = np.random.default_rng(2)
    xs = [random_state(g1, rng, 0.05, 0.2) for _ in range(11)]
    us = [rng.standard_normal(ocp.nu) for _ in range(10)]
    ocp.problem.calc(xs, us)
    mirror.problem.calc(xs, us)
    ocp.problem.calcDiff(xs, us)
    mirror.problem.calcDiff(xs, us)
    for k in range(10):
        for name in ("xnext", "cost", "Fx", "Fu", "Lx", "Lu", "Lxx", "Luu"):
            assert _rel(getattr(ocp.problem.running_datas[k], name),
                        getattr(mirror.problem.runningDatas[k], name)) < 1e-9, f"G1 node {k} {name}"
    ours, theirs, ok_ours, ok_theirs = _solve_both(ocp, mirror, maxiter=5)
    assert ours.iter == theirs.iter
    assert ours.cost == pytest.approx(theirs.cost, rel=1e-9)
    np.testing.assert_allclose(ours.us, np.array(theirs.us), atol=1e-6)


def test_wrench_cone_has_crocoddyls_rows():
    from wbmpc.ocp.residuals.wrench_cone import wrench_cone_matrix

    cone = crocoddyl.WrenchCone(np.eye(3), 0.7, np.array([0.17, 0.05]), 4, True)
    A, lower, upper = wrench_cone_matrix(0.7, 0.085, 0.025)
    ours = sorted(zip(map(tuple, np.round(A, 12)), lower, upper))
    theirs = sorted(zip(map(tuple, np.round(cone.A, 12)), cone.lb, cone.ub))
    assert ours == theirs


def test_offset_wrench_cone_is_crocoddyls_about_the_rectangle_centre():
    """A rectangle centred c along the contact frame's x: Crocoddyl's rows on the wrench moved to that centre."""
    from wbmpc.ocp.residuals.wrench_cone import wrench_cone_matrix

    c = -0.0175
    cone = crocoddyl.WrenchCone(np.eye(3), 0.7, np.array([0.18, 0.02]), 4, True)
    A, _, _ = wrench_cone_matrix(0.7, 0.09, 0.01, center_x=c)
    rng = np.random.default_rng(3)
    for _ in range(5):
        wrench = rng.normal(size=6) * np.array([50.0, 50.0, 300.0, 5.0, 5.0, 2.0])
        moved = pin.Force(wrench[:3], wrench[3:]).se3Action(pin.SE3(np.eye(3), np.array([-c, 0.0, 0.0])))
        theirs = cone.A @ moved.vector
        ours = A @ wrench
        assert sorted(np.round(ours, 9)) == sorted(np.round(theirs, 9))


@needs_h1_extra
@pytest.mark.parametrize("backend", ["pinocchio", "kkt"])
def test_contact_damping_matches_crocoddyls_jminvjt_damping(backend):
    """H1 in double support (rank-deficient contact Jacobian) with contact_damping = Crocoddyl's
    JMinvJt_damping: every node's dynamics, cost and derivatives, with the wrench cone (force
    derivatives) on, and a few FDDP iterations."""
    h1 = load_robot("h1")
    damping = 1e-3
    config = WalkingOCPConfig(wrench_cone_weight=1e2, contact_force_weight=1e-4, baumgarte_gains=(10.0, 30.0),
                              contact_damping=damping, dynamics_backend=backend, evaluation="nodes")
    ocp = WalkingOCP(h1, config, n_nodes=8, dt=0.02)
    # double support on nodes 0-3, then the right foot swings
    schedule = alternating_schedule(0.0, 0.02, 8, step_duration=0.4, foot_y=(0.2, -0.2), t_start=0.07)
    ocp.update(standing_state(h1), schedule, np.array([0.0, 0.0, 0.97]))
    assert ocp.problem.running_models[1].differential.nc == 12
    mirror = CrocoddylMirror(ocp.problem)
    for model in mirror.running_models + [mirror.terminal_model]:
        model.differential.JMinvJt_damping = damping
    rng = np.random.default_rng(5)
    xs = [random_state(h1, rng, 0.02, 0.1) for _ in range(9)]
    us = [rng.standard_normal(ocp.nu) for _ in range(8)]
    ocp.problem.calc(xs, us)
    mirror.problem.calc(xs, us)
    ocp.problem.calcDiff(xs, us)
    mirror.problem.calcDiff(xs, us)
    for k in range(8):
        for name in ("xnext", "cost", "Fx", "Fu", "Lx", "Lu", "Lxx", "Luu"):
            assert _rel(getattr(ocp.problem.running_datas[k], name),
                        getattr(mirror.problem.runningDatas[k], name)) < 1e-9, f"H1 node {k} {name}"
    ours, theirs, _, _ = _solve_both(ocp, mirror, maxiter=3)
    assert ours.iter == theirs.iter
    assert ours.cost == pytest.approx(theirs.cost, rel=1e-8)


@needs_h1_extra
@pytest.mark.filterwarnings("ignore::wbmpc.walking.ocp.SlowPathWarning")  # the H1 is node-wise (its sole damping)
def test_the_h1_preset_has_no_crocoddyl_twin_and_the_loop_bench_says_so():
    """The H1 preset's sole-weighted contact damping and obstacle clearance (a frame point's height) have no
    Crocoddyl model: the mirror refuses the problem by name, and the Crocoddyl loop on the preset reports itself
    skipped with that reason instead of a traceback (``wbmpc bench loop --robot h1`` then runs the baseline on
    the preset's twin-able variant, next test)."""
    from bench.crocoddyl_mirror import NoCrocoddylTwin
    from bench.loop import _crocoddyl_loop
    from wbmpc.cli import build_parser

    h1 = load_robot("h1")
    ocp = WalkingOCP(h1, load_walking_preset("h1").ocp, n_nodes=4, dt=0.02)
    with pytest.raises(NoCrocoddylTwin, match="no Crocoddyl twin for"):
        CrocoddylMirror(ocp.problem)
    args = build_parser().parse_args(["bench", "loop", "--robot", "h1", "--duration", "0.05"])
    result = _crocoddyl_loop(args, None)
    assert result["skipped"].startswith("robot 'h1': its walking OCP has no Crocoddyl twin for ")


@needs_h1_extra
@pytest.mark.filterwarnings("ignore::wbmpc.walking.ocp.SlowPathWarning")  # the H1 is node-wise (its sole damping)
def test_the_h1_presets_crocoddyl_twinnable_variant_replaces_only_the_untwinnable_options():
    """``wbmpc bench loop --robot h1`` compares with Crocoddyl on the preset's twin-able variant: the preset with
    the uniform damping of the same mu (Crocoddyl's JMinvJt_damping) and, in a scenario without obstacles, no
    obstacle clearance terms. The preset's OCP has no twin, the variant's has one, and no other field differs;
    in a scenario with obstacles there is no variant."""
    from bench.crocoddyl_loop import crocoddyl_twinnable_variant
    from bench.crocoddyl_mirror import NoCrocoddylTwin
    from wbmpc.walking.preset import ALL_SECTIONS

    h1 = load_robot("h1")
    preset = load_walking_preset("h1")
    overrides = crocoddyl_twinnable_variant(preset, "walk")
    assert overrides == {"ocp.contact_damping_moments": "uniform", "ocp.obstacle_clearance_weight": 0.0}
    variant = load_walking_preset("h1", overrides)
    differing = {f"{section}.{field.name}" for section in ALL_SECTIONS if getattr(preset, section) is not None
                 for field in dataclasses.fields(getattr(preset, section))
                 if getattr(getattr(preset, section), field.name) != getattr(getattr(variant, section), field.name)}
    assert differing == set(overrides)
    assert (variant.ocp.contact_damping, variant.ocp.dynamics_backend) == (3e-4, "kkt")  # the preset's mu, backend
    with pytest.raises(NoCrocoddylTwin, match="no Crocoddyl twin for"):
        CrocoddylMirror(WalkingOCP(h1, preset.ocp, n_nodes=4, dt=0.02).problem)
    CrocoddylMirror(WalkingOCP(h1, variant.ocp, n_nodes=4, dt=0.02).problem)  # mirrors
    assert crocoddyl_twinnable_variant(variant, "walk") == {}  # twin-able as it is
    with pytest.raises(NoCrocoddylTwin, match=r"obstacle_clearance_weight=100000 in scenario='obstacle'"):
        crocoddyl_twinnable_variant(preset, "obstacle")
