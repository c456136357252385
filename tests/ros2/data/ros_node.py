"""A real ROS 2 node (rclpy) for the ros2 test set, standing for a robot's own drivers.

    python ros_node.py scan TOPIC RANGE        publish a sensor_msgs/msg/LaserScan on TOPIC
                                               at 20 Hz, best effort, every range RANGE m
    python ros_node.py observe FILE TOPIC...   subscribe to geometry_msgs/msg/Twist on
                                               /cmd_vel and std_msgs/msg/String on each TOPIC,
                                               and write each message as a JSON line to FILE
                                               (topic, its fields, the CLOCK_MONOTONIC and the
                                               wall time of its arrival), and every 0.5 s the
                                               nodes it sees

It prints ``ready`` once its publishers and subscriptions exist, and stops on
SIGINT or SIGTERM (rclpy's signal handlers). Its ROS domain and discovery
range come from the environment (ROS_DOMAIN_ID, ROS_AUTOMATIC_DISCOVERY_RANGE).
"""

from __future__ import annotations

import contextlib
import json
import sys
import time

import rclpy
from geometry_msgs.msg import Twist
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import LaserScan
from std_msgs.msg import String


def scan(node: Node, topic: str, distance: float) -> None:
    sensor = QoSProfile(depth=5, reliability=ReliabilityPolicy.BEST_EFFORT)
    publisher = node.create_publisher(LaserScan, topic, sensor)

    def tick() -> None:
        message = LaserScan()
        message.header.stamp = node.get_clock().now().to_msg()
        message.header.frame_id = "laser"
        message.angle_min, message.angle_max, message.angle_increment = -0.5, 0.5, 0.25
        message.range_min, message.range_max = 0.05, 10.0
        message.ranges = [distance] * 5
        publisher.publish(message)

    node.create_timer(0.05, tick)


def observe(node: Node, path: str, topics: list[str]) -> None:
    out = open(path, "a", encoding="utf-8")  # noqa: SIM115  (for the node's life)

    def write(record: dict[str, object]) -> None:
        out.write(json.dumps({**record, "at": time.monotonic(), "wall": time.time()}) + "\n")
        out.flush()

    def twist(message: Twist) -> None:
        write({"topic": "/cmd_vel", "x": message.linear.x, "z": message.angular.z})

    node.create_subscription(Twist, "/cmd_vel", twist, 10)
    for topic in topics:
        latched = QoSProfile(depth=10, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        qos = latched if topic == "/cfgplan/configuration" else 10

        def text(message: String, topic: str = topic) -> None:
            write({"topic": topic, "data": json.loads(message.data)})

        node.create_subscription(String, topic, text, qos)

    def graph() -> None:
        names = sorted(f"{ns.rstrip('/')}/{n}" for n, ns in node.get_node_names_and_namespaces())
        write({"topic": "graph", "nodes": names})

    node.create_timer(0.5, graph)


def main(argv: list[str]) -> None:
    rclpy.init()
    name = f"test_scan{argv[1].replace('/', '_')}" if argv[0] == "scan" else "test_observer"
    node = rclpy.create_node(name)
    if argv[0] == "scan":
        scan(node, argv[1], float(argv[2]))
    else:
        observe(node, argv[1], argv[2:])
    print("ready", flush=True)
    with contextlib.suppress(KeyboardInterrupt, ExternalShutdownException):
        rclpy.spin(node)


if __name__ == "__main__":
    main(sys.argv[1:])
