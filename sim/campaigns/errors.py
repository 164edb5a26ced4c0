"""Errors of the campaign layer (on top of ``wbmpc.errors``)."""

from wbmpc.errors import ParameterError, WbmpcError


class CampaignError(WbmpcError):
    """A campaign cannot go on (a worker process died, the results directory belongs to another campaign)."""


class BackendNotAvailable(CampaignError, ParameterError):
    """The requested backend is unknown or its package is not installed (the message says what to install)."""


class CampaignDirectoryError(CampaignError, ParameterError):
    """The results directory holds another campaign, or records that ``--resume`` was not asked to keep."""
