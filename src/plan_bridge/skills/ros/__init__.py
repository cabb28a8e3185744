"""A skill map's ROS 2 entries: ``ros_action``, ``ros_service`` and ``ros_topic`` in a
domain folder's ``skills.toml``, calling any robot's servers.

* :mod:`~plan_bridge.skills.ros.entries`: the entries read and checked (:class:`RosEntry`);
* :mod:`~plan_bridge.skills.ros.types`: ``pkg/kind/Name`` resolved, messages filled
  from plain data and back;
* :mod:`~plan_bridge.skills.ros.conditions`: conditions on message fields;
* :mod:`~plan_bridge.skills.ros.skill_states`: :class:`RosSkill` (the factory an entry
  registers) and :class:`RosCall`, on smach.ros's states on the default node;
* :mod:`~plan_bridge.skills.ros.probe`: ``--probe``, whether the servers are up.

rclpy is imported only when such a step runs or the probe looks at the graph. The
project's own robot node (``run --ros``) is :mod:`plan_bridge.ros`.
"""
