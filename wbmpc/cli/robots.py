"""``wbmpc robot NAME``: print a robot description's key numbers (``--json`` for a dict)."""

from __future__ import annotations

import argparse

from wbmpc.cli.output import add_output_arguments, print_json


def register(subparsers) -> None:
    from robots.registry import available_robots

    parser = subparsers.add_parser("robot", help="show a robot description (masses, limits, reference posture)")
    parser.add_argument("name", help=f"robot name ({', '.join(available_robots())})")
    add_output_arguments(parser, plot=False)
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from robots.registry import load_robot

    summary = load_robot(args.name).summary()
    if args.json:
        print_json(summary)
    else:
        print(format_summary(summary))
    return 0


def format_summary(summary: dict) -> str:
    """Human-readable table of :meth:`RobotDescription.summary`."""
    lines = [
        f"robot {summary['name']}: nq={summary['nq']} nv={summary['nv']} nu={summary['nu']}, "
        f"mass {summary['mass_kg']:.3f} kg, {summary['contact_type']} contacts at {summary['foot_frames']}",
        f"reference posture: base z {summary['base_height_reference_m']:.4f} m, "
        f"CoM z {summary['com_height_reference_m']:.4f} m (feet on the floor z = 0)",
        f"{'joint':<28}{'torque limit [N·m]':>20}{'armature [kg·m²]':>20}{'velocity limit [rad/s]':>24}",
    ]
    for name, tau, arm, vel in zip(summary["actuated_joint_names"], summary["torque_limit_Nm"],
                                   summary["armature_kg_m2"], summary["velocity_limit_rad_s"]):
        lines.append(f"{name:<28}{tau:>20.3f}{arm:>20.3e}{vel:>24.1f}")
    lines.append("sources:")
    lines.extend(f"  {key}: {value}" for key, value in summary["sources"].items())
    return "\n".join(lines)
