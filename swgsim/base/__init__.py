"""What every part of the project stands on: typed configs (:mod:`swgsim.base.typed`)
and lazily imported package attributes (:mod:`swgsim.base.lazy`)."""
