"""Missions of orders: goals that arrive while a mission runs (``run --orders``).

* :mod:`~plan_bridge.orders.order`: an order and its statuses;
* :mod:`~plan_bridge.orders.book`: :class:`OrderBook`, every order of a mission;
* :mod:`~plan_bridge.orders.order_file`: orders files (orders and Poisson streams);
* :mod:`~plan_bridge.orders.requests`: :class:`OrderDesk`, orders sent to a running
  mission (control API, viewer, ROS 2);
* :mod:`~plan_bridge.orders.assignment`: which steps and robots serve which order;
* :mod:`~plan_bridge.orders.order_executive`: :class:`OrderExecutive`, the mission's
  loop.

See docs/orders.md.
"""
