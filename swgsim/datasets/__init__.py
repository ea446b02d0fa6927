"""Data sets: from a config to schema-v1 files on disk.

In floor order (each module imports only those above it in this list):

- :mod:`~swgsim.datasets.schedule` - a gear life's duty cycle, commissioning and fault
  schedule; :mod:`~swgsim.datasets.profile_config` - an operating profile's typed config;
  :mod:`~swgsim.datasets.config` - the typed data-set config (defaults: the paper preset),
  its rules, each gear's parameters and gauge layout; :mod:`~swgsim.datasets.schema` -
  schema v1 on disk (write, verify, load);
- :mod:`~swgsim.datasets.slots` - the windows of a profile cycle a life records;
  :mod:`~swgsim.datasets.plan` - the config checked in one pass, the shards listed;
- :mod:`~swgsim.datasets.steps` - what the shard runners share (influences, fine motion);
  the runners :mod:`~swgsim.datasets.grid_shard`, :mod:`~swgsim.datasets.profile_shard`
  and :mod:`~swgsim.datasets.life` (with its :mod:`~swgsim.datasets.records`);
- :mod:`~swgsim.datasets.outdir`, :mod:`~swgsim.datasets.resources` - the output folder,
  disk and memory; :mod:`~swgsim.datasets.generate` - orchestration and the runners'
  dispatch.
"""
