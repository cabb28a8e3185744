"""plan_bridge: PDDL planning on top of SMACH (placeholder, replaced below)."""
