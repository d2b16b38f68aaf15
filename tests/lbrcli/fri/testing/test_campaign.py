"""A campaign case's verdict: within the limits means velocity, acceleration and — unless the case says its client's
jerk is its own — jerk."""

from __future__ import annotations

import dataclasses

from lbrcli.campaign.surfaces import all_surfaces, surface_cases
from lbrcli.fri.testing.campaign import CaseResult

BASE = CaseResult("c", "cat", "execute", "ok", "finished", "", 0.5, 0.9, 0.99, 0.0, False, 0.0, 0, None, True, 10, True)


def test_a_command_beyond_the_jerk_limit_fails_a_case_unless_its_jerk_is_the_clients_own():
    assert BASE.within_limits and BASE.ok
    over = dataclasses.replace(BASE, jerk_ratio=1.16)
    assert not over.within_limits and not over.ok
    assert dataclasses.replace(over, jerk_judged=False).ok  # a user's client that asks for jumps
    assert not dataclasses.replace(BASE, acceleration_ratio=1.01, jerk_judged=False).ok


def test_only_a_users_own_client_is_spared_the_jerk_judgement():
    spared = {c.surface for s in all_surfaces() for c in surface_cases(s) if not c.jerk_judged}
    assert spared == {"user"}
