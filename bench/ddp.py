"""FDDP and MPC tick of wbmpc against Crocoddyl on the identical Bolt (and G1) walking problem.

For each horizon N: a cold solve, one iteration split into calc / calcDiff / backward / forward,
and the receding-horizon MPC tick (shift, warm start, one iteration), median / p90 / p99 / max,
each with the ratio ours / Crocoddyl measured in the same run (both single-threaded; the two
solvers alternate tick by tick so machine noise hits both alike). The problems are built once by
``wbmpc.walking.ocp`` and mirrored into Crocoddyl by :mod:`bench.crocoddyl_mirror`. Bolt's is
the default ``WalkingOCPConfig``; G1's the G1 preset's OCP (6D sole contacts, wrench cones,
swing-sole orientation: what its closed loop solves), from both feet on the ground.

With ``--time-budget`` a third MPC, ours with that budget per tick (``WalkingMPC(time_budget=)``),
runs in the same loop on the same measured states: its tick times, how many ticks the budget cut
short, and how far its applied torque u₁ moved from the unbudgeted one.

Our MPC runs as a real-time loop would use it: after each update, ``WalkingMPC.prepare``
computes the next update's contact-dynamics derivatives before the next measurement. Its tick is
then reported twice: the update (measurement to solution, what a 100 Hz deadline bounds) and the
cycle (update + the preparation made for it, the work per period), each against Crocoddyl's tick.
``--no-prepare`` times the update alone, everything computed after the measurement.
"""

from __future__ import annotations

import argparse
import gc
import time

import numpy as np

G1_T_START = 0.2  # [s] both G1 feet on the ground until then in the MPC loop


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--nodes", type=int, nargs="+", default=[50, 100], help="horizon lengths N (dt = 10 ms)")
    parser.add_argument("--ticks", type=int, default=200, help="MPC ticks timed per horizon")
    parser.add_argument("--repeats", type=int, default=20, help="repetitions of the per-phase iteration timing")
    parser.add_argument("--g1-nodes", type=int, default=50, help="G1 horizon (dt = 20 ms); 0 skips G1")
    parser.add_argument("--seed", type=int, default=0, help="seed of the state disturbances of the MPC loop")
    parser.add_argument("--horizon-end", choices=("rollout", "repeat"), default="rollout",
                        help="warm-start fill of the Bolt MPC's horizon end (the closed loop's: rollout; G1: repeat)")
    parser.add_argument("--time-budget", type=float, default=None, metavar="S",
                        help="also time our MPC with this budget per tick [s], e.g. 0.009 (real-time deadline)")
    parser.add_argument("--no-prepare", action="store_true",
                        help="do not prepare the next update's derivatives ahead (WalkingMPC.prepare)")


def _stats(samples) -> dict:
    a = np.asarray(samples, dtype=float) * 1e3
    return {"median_ms": float(np.median(a)), "p90_ms": float(np.percentile(a, 90)),
            "p99_ms": float(np.percentile(a, 99)), "max_ms": float(np.max(a)), "n": int(a.size)}


def _ratio(ours: dict, theirs: dict) -> dict:
    return {key: ours[key] / theirs[key] for key in ("median_ms", "p90_ms", "p99_ms", "max_ms")}


def _schedule(t0: float, dt: float, n_nodes: int, step_duration: float, foot_y=(0.1, -0.1), step_length=0.1,
              t_start: float = 0.0):
    """Both feet on the ground before ``t_start`` [s], then an alternating single-support gait
    starting with the right swing."""
    from sequencer.schedule import ContactSchedule

    times = t0 + dt * np.arange(n_nodes + 1)
    in_contact = np.ones((n_nodes + 1, 2), dtype=bool)
    phase = np.full((n_nodes + 1, 2), np.nan)
    duration = np.full((n_nodes + 1, 2), np.nan)
    touchdown = np.full((n_nodes + 1, 2, 2), np.nan)
    for k, t in enumerate(times):
        if t < t_start - 1e-9:
            continue
        step = int(np.floor((t - t_start) / step_duration + 1e-9))
        swing = 1 if step % 2 == 0 else 0
        in_contact[k, swing] = False
        phase[k, swing] = (t - t_start - step * step_duration) / step_duration
        duration[k, swing] = step_duration
        touchdown[k, swing] = ((step + 1) * step_length, foot_y[swing])
    return ContactSchedule(t0=t0, dt=dt, feet=("left", "right"), in_contact=in_contact, swing_phase=phase,
                           swing_duration=duration, touchdown_position=touchdown)


def _mpc_loop(robot, config, n_nodes: int, dt: float, step_duration: float, foot_y, ticks: int, seed: int,
              speed: float = 0.3, time_budget: float | None = None, horizon_end: str = "repeat",
              prepare: bool = True, t_start: float = 0.0) -> dict:
    """Run both MPCs (and ours with ``time_budget``) on the same measured states; returns tick
    statistics and the control gaps. With ``prepare``, ours runs ``WalkingMPC.prepare`` after each
    update (timed apart): its tick is the update (measurement to solution), its cycle the update
    plus the preparation made for it."""
    import crocoddyl

    from bench.crocoddyl_mirror import CrocoddylMirror
    from wbmpc.walking.mpc import WalkingMPC
    from wbmpc.walking.ocp import quasi_static_controls

    mpc = WalkingMPC(robot, config, n_nodes=n_nodes, dt=dt, max_iterations=1, cold_start_iterations=20,
                     horizon_end=horizon_end)
    budgeted = None if time_budget is None else WalkingMPC(robot, config, n_nodes=n_nodes, dt=dt, max_iterations=1,
                                                          cold_start_iterations=20, horizon_end=horizon_end,
                                                          time_budget=time_budget)
    budget_times, budget_hits, budget_gap = [], 0, 0.0
    mirror = CrocoddylMirror(mpc.problem)
    twin = crocoddyl.SolverFDDP(mirror.problem)
    nq, nv = mpc.ocp.state.nq, mpc.ocp.state.nv
    x = np.concatenate([robot.q_reference, np.zeros(nv)])
    com0 = np.array([0.0, 0.0, 0.0])
    import pinocchio as pin

    com0 = pin.centerOfMass(robot.pinocchio_model, robot.pinocchio_model.createData(), x[:nq]).copy()
    rng = np.random.default_rng(seed)
    ours_times, theirs_times, prepare_times = [], [], []
    prepared = 0.0
    # As a real-time loop would (sim.runner does): move the models, solvers and compiled code out
    # of the collector's reach; a full collection in this process takes 28-81 ms, and none may
    # land inside a timed tick (of either solver).
    gc.collect()
    gc.freeze()
    gap = 0.0
    for tick in range(ticks + 1):
        t = tick * dt
        schedule = _schedule(t, dt, n_nodes, step_duration, foot_y, t_start=t_start)
        com_ref = com0 + np.array([speed * (t + n_nodes * dt), 0.0, 0.0])
        if tick > 0:  # the guess our update is about to make, for Crocoddyl (not timed)
            mpc.ocp.update(x, schedule, com_ref)
            guess_xs, guess_us, _ = mpc.warm_start(t, x)
        tic = time.perf_counter()
        solution = mpc.update(t, x, schedule, com_ref)
        ours = time.perf_counter() - tic
        if tick > 0:  # tick 0 is the cold start; the preparation timed is the one made for this update
            ours_times.append(ours)
            prepare_times.append(prepared)
        if prepare:
            tic = time.perf_counter()
            mpc.prepare()
            prepared = time.perf_counter() - tic
        mirror.update()  # copies references and x0 into the twin (not timed: a C++ user sets them directly)
        tic = time.perf_counter()
        if tick == 0:
            twin.solve([x] * (n_nodes + 1), [quasi_static_controls(mpc.ocp, x)] * n_nodes, 20)
        else:  # the same guess as ours: the shifted plan, its end filled as horizon_end says
            twin.solve(list(guess_xs), list(guess_us), 1)
        theirs = time.perf_counter() - tic
        if tick > 0:
            theirs_times.append(theirs)
        if budgeted is not None:
            tic = time.perf_counter()
            cut = budgeted.update(t, x, schedule, com_ref)
            if tick > 0:
                budget_times.append(time.perf_counter() - tic)
                budget_hits += cut.status == "deadline"
            if not cut.ok:
                raise RuntimeError(f"wbmpc MPC with a time budget failed at tick {tick}: {cut.status}")
            if prepare:
                budgeted.prepare()
            budget_gap = max(budget_gap, float(np.max(np.abs(cut.us[1] - solution.us[1]))))
        if not solution.ok:
            raise RuntimeError(f"wbmpc MPC failed at tick {tick}: {solution.status}")
        gap = max(gap, float(np.max(np.abs(solution.us[1] - np.asarray(twin.us[1])))))
        x = solution.xs[1].copy()
        x[nq:] += 0.01 * rng.standard_normal(nv)
    ours_stats, theirs_stats = _stats(ours_times), _stats(theirs_times)
    result = {"ours": ours_stats, "crocoddyl": theirs_stats, "ratio": _ratio(ours_stats, theirs_stats),
              "max_control_difference_Nm": gap, "prepare": prepare}
    if prepare:
        cycle = _stats(np.add(ours_times, prepare_times))
        result.update(ours_prepare=_stats(prepare_times), ours_cycle=cycle, cycle_ratio=_ratio(cycle, theirs_stats))
    if budgeted is not None:
        result["budgeted"] = {"time_budget_s": time_budget, **_stats(budget_times), "deadline_ticks": budget_hits,
                              "max_control_difference_to_unbudgeted_Nm": budget_gap}
    return result


def _phases(robot, config, n_nodes: int, dt: float, repeats: int) -> dict:
    """Cold solve and one iteration split into phases, ours and Crocoddyl's."""
    import crocoddyl

    from bench.crocoddyl_mirror import CrocoddylMirror
    from wbmpc.ocp.solvers import SolverFDDP
    from wbmpc.walking.ocp import WalkingOCP, quasi_static_controls

    ocp = WalkingOCP(robot, config, n_nodes=n_nodes, dt=dt)
    x0 = np.concatenate([robot.q_reference, np.zeros(robot.pinocchio_model.nv)])
    ocp.update(x0, _schedule(0.0, dt, n_nodes, 0.3), np.array([0.3, 0.0, 0.3]))
    mirror = CrocoddylMirror(ocp.problem)
    u0 = quasi_static_controls(ocp, x0)
    xs0, us0 = [x0] * (n_nodes + 1), [u0] * n_nodes
    ours, theirs = SolverFDDP(ocp.problem), crocoddyl.SolverFDDP(mirror.problem)
    ours.solve(xs0, us0, 1)  # compile / warm caches
    tic = time.perf_counter()
    ours.solve(xs0, us0, 100)
    cold_ours = time.perf_counter() - tic
    tic = time.perf_counter()
    theirs.solve(xs0, us0, 100)
    cold_theirs = time.perf_counter() - tic
    iterations = (ours.iter, theirs.iter)
    xs, us = ours.xs.copy(), ours.us.copy()
    names = ("calc", "calcDiff", "backward", "forward")
    samples = {"ours": {n: [] for n in names}, "crocoddyl": {n: [] for n in names}}
    for _ in range(repeats):
        ours._set_candidate(xs, us, False)
        ours.iter = 0
        for name, fn in (("calc", lambda: ocp.problem.calc(ours.xs, ours.us)),
                         ("calcDiff", lambda: (ocp.problem.calcDiff(ours.xs, ours.us), ours._compute_gaps())),
                         ("backward", ours._backward_pass),
                         ("forward", lambda: ours._forward_pass(1.0))):
            tic = time.perf_counter()
            fn()
            samples["ours"][name].append(time.perf_counter() - tic)
        lxs, lus = list(xs), list(us)
        theirs.setCandidate(lxs, lus, False)
        for name, fn in (("calc", lambda lxs=lxs, lus=lus: mirror.problem.calc(lxs, lus)),
                         ("calcDiff", theirs.calcDiff),
                         ("backward", theirs.backwardPass),
                         ("forward", lambda: theirs.forwardPass(1.0))):
            tic = time.perf_counter()
            fn()
            samples["crocoddyl"][name].append(time.perf_counter() - tic)
    result = {"cold_solve": {"ours_s": cold_ours, "crocoddyl_s": cold_theirs, "ratio": cold_ours / cold_theirs,
                             "ours_iterations": iterations[0], "crocoddyl_iterations": iterations[1]}}
    for name in names:
        o = float(np.median(samples["ours"][name])) * 1e3
        c = float(np.median(samples["crocoddyl"][name])) * 1e3
        result[name] = {"ours_ms": o, "crocoddyl_ms": c, "ratio": o / c}
    return result


def run(args: argparse.Namespace) -> dict:
    from robots import load_robot
    from wbmpc.ocp.blas import limit_blas_threads
    from wbmpc.walking.ocp import WalkingOCPConfig
    from wbmpc.walking.preset import load_walking_preset

    with limit_blas_threads(1):  # both solvers single-threaded, for this run only
        for n in args.nodes:
            if n < 2:
                raise ValueError(f"--nodes {n}: every horizon must have at least 2 nodes")
        bolt = load_robot("bolt")
        config = WalkingOCPConfig()
        result = {"robot": "bolt", "dt_s": 0.01, "horizon_end": args.horizon_end, "horizons": {}}
        for n_nodes in args.nodes:
            entry = _phases(bolt, config, n_nodes, 0.01, args.repeats)
            entry["mpc_tick"] = _mpc_loop(bolt, config, n_nodes, 0.01, 0.3, (0.1, -0.1), args.ticks, args.seed,
                                          time_budget=args.time_budget, horizon_end=args.horizon_end,
                                          prepare=not args.no_prepare)
            result["horizons"][str(n_nodes)] = entry
        if args.g1_nodes:
            # the G1 preset's OCP (6D sole contacts, wrench cones, swing-sole orientation), starting
            # from both feet on the ground (from standing, the first swing at once does not converge)
            g1 = load_robot("g1")
            result["g1"] = {"n_nodes": args.g1_nodes, "dt_s": 0.02, "ocp": "preset g1", "t_start_s": G1_T_START,
                            "mpc_tick": _mpc_loop(g1, load_walking_preset("g1").ocp, args.g1_nodes, 0.02, 0.4,
                                                  (0.12, -0.12), max(20, args.ticks // 4), args.seed, speed=0.2,
                                                  prepare=not args.no_prepare, t_start=G1_T_START)}
    return result


def format_report(result: dict) -> str:
    lines = ["wbmpc FDDP vs Crocoddyl (single thread, same problem, same run); ratio = ours / Crocoddyl"]
    for n, entry in result["horizons"].items():
        cold = entry["cold_solve"]
        lines.append(f"\nBolt N={n} (dt {result['dt_s'] * 1e3:.0f} ms, MPC horizon end: {result['horizon_end']})")
        lines.append(f"  cold solve      ours {cold['ours_s'] * 1e3:9.1f} ms ({cold['ours_iterations']} it)   "
                     f"crocoddyl {cold['crocoddyl_s'] * 1e3:8.1f} ms ({cold['crocoddyl_iterations']} it)   "
                     f"ratio {cold['ratio']:5.2f}")
        for phase in ("calc", "calcDiff", "backward", "forward"):
            p = entry[phase]
            lines.append(f"  {phase:<14}  ours {p['ours_ms']:9.3f} ms   crocoddyl {p['crocoddyl_ms']:8.3f} ms   "
                         f"ratio {p['ratio']:5.2f}")
        lines.extend(_tick_lines(entry["mpc_tick"]))
    if "g1" in result:
        g1 = result["g1"]
        lines.append(f"\nG1 N={g1['n_nodes']} (dt {g1['dt_s'] * 1e3:.0f} ms, the preset's OCP: flat feet, wrench cones, "
                     f"swing-sole orientation; double support until {g1['t_start_s']:.1f} s)")
        lines.extend(_tick_lines(g1["mpc_tick"]))
    return "\n".join(lines)


def _tick_lines(tick: dict) -> list[str]:
    o, c, r = tick["ours"], tick["crocoddyl"], tick["ratio"]
    row = lambda name, s: f"    {name:<22} {s['median_ms']:7.2f} {s['p90_ms']:7.2f} {s['p99_ms']:7.2f} {s['max_ms']:7.2f}"  # noqa: E731
    lines = [f"  MPC tick ({o['n']} ticks)             median / p90 / p99 / max [ms]"]
    if tick.get("prepare"):
        lines.append(row("ours, update", o) + "   (measurement to solution)")
        lines.append(row("ours, prepare", tick["ours_prepare"]) + "   (before the measurement, WalkingMPC.prepare)")
        lines.append(row("ours, cycle", tick["ours_cycle"]) + "   (update + its preparation)")
    else:
        lines.append(row("ours", o))
    lines.append(row("crocoddyl", c) + "   (update = cycle)")
    lines.append(row("ratio update" if tick.get("prepare") else "ratio", r))
    if tick.get("prepare"):
        lines.append(row("ratio cycle", tick["cycle_ratio"]))
    lines.append(f"    max |u1 ours - u1 crocoddyl| = {tick['max_control_difference_Nm']:.2e} N·m")
    if "budgeted" in tick:
        b = tick["budgeted"]
        lines.append(row(f"ours, {b['time_budget_s'] * 1e3:.1f} ms budget", b) + "   "
                     f"({b['deadline_ticks']} of {b['n']} ticks cut short; max |u1 - u1 unbudgeted| = "
                     f"{b['max_control_difference_to_unbudgeted_Nm']:.2e} N·m)")
    return lines
