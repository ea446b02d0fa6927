"""The apps' composed configs as typed objects: the one place where a task turns a
config into the dataclasses that travel on (:func:`typed_app`)."""

from __future__ import annotations

from typing import Any


def typed_app(cfg: Any) -> Any:
    """An app's whole composed config as its schema's dataclass, every group typed.

    Parameters
    ----------
    cfg : omegaconf.DictConfig or dataclass
        A config composed on a structured schema (``swgcli.schema.TrainApp``), or the
        typed object already (returned unchanged).

    Returns
    -------
    dataclass
        ``OmegaConf.to_object(cfg)``: interpolations resolved, the groups as their
        dataclasses (:class:`learn.inputs.features.FeatureSettings`,
        :class:`learn.studies.protocols.ProtocolConfig`,
        :class:`learn.tracking.config.LoggerConfig`,
        :class:`learn.paper.tables.StudyOptions`,
        :class:`learn.transfer.study.TransferConfig`, ...); ``_target_`` configs (the
        models) stay mappings for :func:`hydra.utils.instantiate`.

    Raises
    ------
    omegaconf.errors.MissingMandatoryValue
        A mandatory value left at ``???`` (e.g. a run of ``transfer.runs`` without its
        ``model``).
    """
    from omegaconf import DictConfig, OmegaConf

    return OmegaConf.to_object(cfg) if isinstance(cfg, DictConfig) else cfg
