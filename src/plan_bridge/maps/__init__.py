"""What every world with places needs: its map, the goals over it, and the tasks a
planner gets of it.

* :mod:`.model`: a world as the task level sees it (places, hallways, gates, objects,
  robots), plain data;
* :mod:`.graph`: the map, a networkx graph of places, and routes over open hallways;
* :mod:`.goals`: goals in pyrobosim's vocabulary, checked against a world's names, and
  :mod:`.blockers`: why no run can reach one;
* :mod:`.tasks`: the task view: a small task for the belief and a goal (the places it
  needs, routes between them), built in memory for the map domain (``domain.pddl``).

pyrobosim worlds are read into a model by :mod:`plan_bridge.robosim.description`;
nothing here imports pyrobosim.
"""
