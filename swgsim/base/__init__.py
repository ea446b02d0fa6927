"""What every part of the project stands on: typed configs (:mod:`swgsim.base.typed`),
lazily imported package attributes (:mod:`swgsim.base.lazy`), the one registry type
of the extension points (:mod:`swgsim.base.registry`) and the one writer of the reports'
markdown tables (:mod:`swgsim.base.markdown`)."""
