"""Introspection: the event stream, structure snapshots and their renderings."""
