"""avoid: slow down near an obstacle; laser and drive are ROS 2 topics (drive-map.toml)."""

from cfgplan.runtime import functionality


@functionality("avoid")
def avoid(scan: dict) -> dict:  # type: ignore[type-arg]
    """A geometry_msgs/msg/Twist from a sensor_msgs/msg/LaserScan: 0.5 m/s if clear, else 0."""
    ranges = [r for r in scan["ranges"] if r > 0]
    speed = 0.5 if ranges and min(ranges) > 1.0 else 0.0
    return {"linear": {"x": speed}, "angular": {"z": 0.1}}
