"""Errors a user can act on.

Every problem with the user's input or with a run raises a subclass of :class:`PartyError`
whose message is one line naming the thing at fault. The CLI prints that line and exits
non-zero; library users catch ``PartyError``.
"""


INTERRUPTED = 130
"""Exit status of a run stopped by Ctrl-C (SIGINT), as shells give it."""


class PartyError(ValueError):
    """Base class: a one-line, user-facing problem."""


class InvalidInput(PartyError):
    """A parameter, mesh or file the user gave is unusable (names which and why)."""


class SimulationUnstable(PartyError):
    """The integration blew up (non-finite or runaway velocities)."""


class WorkersLost(PartyError):
    """CPU threads sharing a launch (:func:`party.launch.launch_workers`) waited for one another
    in vain; one thread (``PARTY_THREADS=1``) avoids them."""
