"""Registry of robot descriptions: ``load_robot(name)`` and the ``@register_robot`` decorator.

Adding a robot is one module: write a function that returns a :class:`RobotDescription`,
decorate it with ``@register_robot("name")`` and import the module in ``robots/__init__.py``.
"""

from __future__ import annotations

from typing import Callable

from robots.description import RobotDescription
from wbmpc.errors import ParameterError

RobotBuilder = Callable[[], RobotDescription]

_BUILDERS: dict[str, RobotBuilder] = {}


def register_robot(name: str) -> Callable[[RobotBuilder], RobotBuilder]:
    """Decorator registering ``builder() -> RobotDescription`` under ``name``."""
    if not isinstance(name, str) or not name:
        raise ParameterError(f"robot name={name!r} must be a non-empty string")

    def decorator(builder: RobotBuilder) -> RobotBuilder:
        if name in _BUILDERS and _BUILDERS[name] is not builder:
            raise ParameterError(f"robot name={name!r} is already registered (by {_BUILDERS[name].__module__})")
        _BUILDERS[name] = builder
        return builder

    return decorator


def available_robots() -> tuple[str, ...]:
    """Names accepted by :func:`load_robot`, sorted."""
    return tuple(sorted(_BUILDERS))


def load_robot(name: str) -> RobotDescription:
    """Build the description of robot ``name`` ("bolt", "g1", ...).

    Each call builds a new description (its own Pinocchio model); building Bolt takes a few
    milliseconds (no meshes are loaded on the Pinocchio side).

    Raises:
        ParameterError: ``name`` is not a registered robot (the message lists the available ones).
    """
    if isinstance(name, RobotDescription):
        return name
    check_robot_name(name)
    return _BUILDERS[name]()


def check_robot_name(name: str) -> None:
    """Raise ParameterError (listing the available robots) unless ``name`` is a registered robot."""
    if not isinstance(name, str) or name not in _BUILDERS:
        raise ParameterError(f"robot={name!r} is not known; available robots: {', '.join(available_robots())}")
