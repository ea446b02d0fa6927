"""The gear and its physics: what is simulated before any sensor reads it (dynamics,
profiles, the flexspline truss, gauges, the simulation chain, faults, friction; each module:
docs/ARCHITECTURE.md, "Layout").
"""
