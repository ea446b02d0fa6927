"""Files, integrity and provenance: the floor every other part of ``swgsim`` stands on.

- :mod:`swgsim.files.atomic`: atomic replacement of a file, the names of temporary files
  and whether the process that left one still runs;
- :mod:`swgsim.files.digest`: SHA-256 of files and of plain configs;
- :mod:`swgsim.files.ownership`: ownership stamps (a run deletes or overwrites only what it
  can prove it wrote) and the writes recorded in them (:func:`~swgsim.files.ownership.
  atomic_write_bytes`, :func:`~swgsim.files.ownership.atomic_write_json`);
- :mod:`swgsim.files.stamp`: the stamp as a file (names, reading, locked atomic updates);
- :mod:`swgsim.files.writers`: which app and kind of output wrote each file (an app
  replaces only its own kind);
- :mod:`swgsim.files.provenance`: the package version, git commit and library versions a
  result was made with.

Nothing here knows about gears or data sets.
"""
