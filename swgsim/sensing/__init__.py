"""The measurement chain: what happens between the flexspline's strain and the recorded
numbers (sensor effects, the bench amplifier, angle channels, eq. (10), sensor faults, the
bridges' drift; each module: docs/ARCHITECTURE.md, "Layout").
"""
