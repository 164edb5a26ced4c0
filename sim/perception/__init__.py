"""Rangefinder perception of the ground ahead (issue 15): MuJoCo sensors, scans, a height map and the
obstacles the walking controller is told about (``Measurement.obstacles``).

- :mod:`sim.perception.layout`: ray directions in the base frame, site orientations;
- :mod:`sim.perception.rangefinder`: the sensors in the robot's ``MjSpec``, read at their rate, faults;
- :mod:`sim.perception.scan`: one scan and its world points (from the measured base pose);
- :mod:`sim.perception.heightmap`: the height map with memory;
- :mod:`sim.perception.terrain`: ground level and obstacles from the map;
- :mod:`sim.perception.pipeline`: the three in the closed loop (what the runner calls), with its log.

The configuration is the walking preset's optional ``[perception]`` section
(:class:`wbmpc.walking.perception_config.PerceptionConfig`); docs/perception.md has the layout, the
measured errors and the faults.
"""

from sim.perception.heightmap import HeightMap
from sim.perception.layout import quaternion_z_to, ray_directions_base
from sim.perception.pipeline import PerceptionPipeline
from sim.perception.rangefinder import RangefinderArray, add_rangefinders
from sim.perception.scan import Scan
from sim.perception.terrain import ObstacleTrack, TerrainEstimator

__all__ = ["HeightMap", "ObstacleTrack", "PerceptionPipeline", "RangefinderArray", "Scan", "TerrainEstimator",
           "add_rangefinders", "quaternion_z_to", "ray_directions_base"]
