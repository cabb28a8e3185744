"""The belief: what the executive thinks is true of the world (a room of its own).

* :mod:`~plan_bridge.belief.facts`: fact snapshots with numeric values, observations;
* :mod:`~plan_bridge.belief.belief`: :class:`Belief`, the thread-safe believed state.
"""

from plan_bridge.belief.belief import Belief as Belief
from plan_bridge.belief.facts import FactSnapshot as FactSnapshot
from plan_bridge.belief.facts import Observation as Observation
from plan_bridge.belief.facts import describe_observation as describe_observation
from plan_bridge.belief.facts import normalise_observations as normalise_observations
from plan_bridge.belief.facts import values_of as values_of
