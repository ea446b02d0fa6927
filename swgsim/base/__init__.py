"""What every part of the project stands on: typed configs (:mod:`swgsim.base.typed`),
lazily imported package attributes (:mod:`swgsim.base.lazy`) and the one registry type
of the extension points (:mod:`swgsim.base.registry`)."""
