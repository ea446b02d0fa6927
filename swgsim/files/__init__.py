"""Files, integrity and provenance: the floor every other part of ``swgsim`` stands on
(atomic writes, digests, ownership stamps and their writers, input-file checks, provenance;
each module: docs/ARCHITECTURE.md, "Layout"). Nothing here knows about gears or data sets.
"""
