"""What happened to the ball in one run of the string model: caught or not, and why — from the run's events.

Used for every run the same way: the planner's band members (``string_stepper``), its prediction and final band
(``string_sim``), the FRI simulator's ball and the benchmarks' judges.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

from .string_sim import BallEvent


@dataclass(frozen=True)
class CatchOutcome:
    """Caught (resting in the cup at the end), when the ball first entered the cup [s] and came to rest [s], the
    entry margin to the rim [m] ((R − r) − ρ where the ball centre first crosses the rim plane downward: > 0 it
    fits through the opening), the relative entry speed [m/s] and its lateral part, and the reason when not."""

    caught: bool
    t_release: float | None  # [s] first time the string went slack
    t_entry: float | None  # [s] first downward crossing of the rim plane inside the opening
    t_rest: float | None  # [s] the ball came to rest in the cup (the last time it did)
    margin: float | None  # [m] at the first downward crossing of the rim plane (None: it never crossed it)
    relative_speed: float | None  # [m/s] at that crossing
    lateral_speed: float | None  # [m/s] its part across the cup axis
    t_crossing: float | None  # [s] of that crossing
    contacts: int
    retension_before_entry: float | None  # [s] the string tightened again before the ball reached the cup
    failure: str | None

    def figures(self) -> dict:
        return {
            "caught": self.caught,
            "t_release_s": self.t_release,
            "t_entry_s": self.t_entry,
            "t_rest_s": self.t_rest,
            "entry_margin_m": self.margin,
            "relative_entry_speed_m_s": self.relative_speed,
            "relative_lateral_speed_m_s": self.lateral_speed,
            "contacts": self.contacts,
            "failure": self.failure,
        }


def outcome(events: Sequence[BallEvent], resting: bool, inside: bool) -> CatchOutcome:
    """Summarise a run from its events (time order) and its final state (resting on the cup, centre inside it)."""
    slack = [e for e in events if e.kind == "slack"]
    crossings = [e for e in events if e.kind == "entry"]
    first = crossings[0] if crossings else None
    entries = [e for e in crossings if e.info["margin_m"] > 0.0]
    t_entry = entries[0].t if entries else None
    rests = [e for e in events if e.kind == "rest"]
    t_release = slack[0].t if slack else None
    retension = [
        e
        for e in events
        if e.kind == "retension" and t_release is not None and e.t > t_release and (first is None or e.t < first.t)
    ]
    caught = resting and inside
    failure = None
    if not caught:
        if t_release is None and first is None:
            failure = "the string never goes slack: the ball does not leave its circle"
        elif retension and t_entry is None:
            failure = f"the string tightens again at t = {retension[0].t:.2f} s before the ball reaches the cup"
        elif first is None:
            failure = "the ball never comes down through the rim plane of the cup"
        elif t_entry is None:
            failure = f"ball passes {-first.info['margin_m'] * 1e3:.0f} mm outside the rim at t = {first.t:.2f} s"
        elif resting and not inside:
            failure = f"ball entered at t = {t_entry:.2f} s but ends resting on the rim"
        elif inside:
            failure = f"ball entered at t = {t_entry:.2f} s and is still bouncing in the cup at the end"
        else:
            failure = f"ball entered at t = {t_entry:.2f} s and bounced out"
    return CatchOutcome(
        caught=caught,
        t_release=t_release,
        t_entry=t_entry,
        t_rest=rests[-1].t if rests and caught else None,
        margin=first.info["margin_m"] if first else None,
        relative_speed=(entries[0] if entries else first).info["relative_speed_m_s"] if first else None,
        lateral_speed=(entries[0] if entries else first).info["relative_lateral_speed_m_s"] if first else None,
        t_crossing=first.t if first else None,
        contacts=sum(e.kind == "contact" for e in events),
        retension_before_entry=retension[0].t if retension else None,
        failure=failure,
    )
