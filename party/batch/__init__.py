"""``party batch``: many drapes, unattended, into a dataset with a manifest (:mod:`.run`)."""

from .items import BatchItem, plan
from .manifest import Manifest
from .run import BatchSettings, run_batch

__all__ = ["BatchItem", "BatchSettings", "Manifest", "plan", "run_batch"]
