"""Named joint configurations of the iiwa 7 used as defaults across lbr."""

from __future__ import annotations

THESIS_START = (0.0, 0.071, 0.0, -1.3523, 0.0, 0.1301, 0.0)  # [rad] the thesis' start pose (§5.3.2): flange horizontal
