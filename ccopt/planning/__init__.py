"""Planning over contact configurations: which motions the statics allow where, and sequences of them.

:mod:`.graph` is the search over configurations ``(θ_o, s_h)`` on a grid of the paper's increments,
whose edges are motions the statics (:mod:`ccopt.statics`) allow with margin; it runs on the true
parameters (the experimenter's oracle, e.g. to build schedules of possible steps) or on the estimated
ones (the planner of a run).
"""

from ccopt.planning.graph import ConfigurationGraph, Edge, GraphParams, Node

__all__ = ["ConfigurationGraph", "Edge", "GraphParams", "Node"]
