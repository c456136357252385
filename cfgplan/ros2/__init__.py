"""ROS 2 interoperation over rmw_zenoh, from plain zenoh-python.

:mod:`cfgplan.ros2.rmw_zenoh` is the wire format of ROS 2's Zenoh middleware
(key expressions, liveliness tokens, attachment, CDR payloads) as pure
functions; :mod:`cfgplan.ros2.bridge` publishes a robot's reconfiguration
events as the ROS 2 topic ``/cfgplan/events``, and its global channels as
topics (``cfgplan run --robot NAME --ros2``); :mod:`cfgplan.ros2.topics`
reads the topic map (``--ros2-map FILE``) that binds functionality inputs
and outputs to topics,
:mod:`cfgplan.ros2.bindings` puts those on the robot's session,
:mod:`cfgplan.ros2.codec` turns messages into plain values and back, and
:mod:`cfgplan.ros2.fields` maps several ports to fields of one message. None
imports :mod:`zenoh` at module level; ``rosbags`` and ``xxhash`` (the
``ros2`` extra, ``pip install 'cfgplan[ros2]'``) are imported only when a
payload, type hash or GID is computed.
"""

from __future__ import annotations
