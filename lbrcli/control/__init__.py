"""Feedback controllers as FRI clients (``lbr control ...``): built on :mod:`lbrcli.fri`'s public API and the
algorithms of :mod:`planners.feedback`, so that the FRI library itself imports no planner.

:class:`UprightClient` swings the pendulum module's rod up and balances it; :class:`DampingClient` streams a joint
CSV while the measured sway corrects the TCP's horizontal path.
"""

from .damping import DampingClient
from .upright import UprightClient

__all__ = ["DampingClient", "UprightClient"]
