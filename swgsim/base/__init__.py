"""What every part of the project stands on: typed configs (:mod:`swgsim.base.typed`),
lazily imported package attributes (:mod:`swgsim.base.lazy`) and old module paths kept
for a release (:mod:`swgsim.base.moved`)."""
