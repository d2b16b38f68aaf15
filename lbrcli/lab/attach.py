"""The pendulum module and MQTT telemetry attached to an FRI session.

Both run off the FRI loop: the loop only reads the reader's newest reading for the log row, and at the telemetry
rate copies a few dozen numbers into a dict that the publisher's thread serialises and sends.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

from .pendulum_serial import PendulumReader
from .telemetry import TelemetryPublisher, parse_mqtt_url

PENDULUM_COLUMNS = ("pend_theta", "pend_omega", "pend_age")  # [rad], [rad/s], [s] since the reading arrived
_STATES = ("IDLE", "MONITORING_WAIT", "MONITORING_READY", "COMMANDING_WAIT", "COMMANDING_ACTIVE")


@dataclass(frozen=True)
class LabOptions:
    """What the user attached: a serial port ('sim': the simulator's emulated module), an MQTT URL. Checked when
    made (SettingError naming the field); :meth:`validate` checks them against the session."""

    pendulum: str | None = None  # serial port of the pendulum module; "sim": the simulator's on a pseudo-terminal
    baud: int = 115200  # [1/s] of the module's serial line
    pendulum_zero: int = 0  # encoder count of the hanging pendulum
    mqtt: str | None = None  # mqtt://[USER:PASSWORD@]HOST:PORT/TOPIC the state is published to
    mqtt_rate_hz: float = 50.0  # [Hz] telemetry messages per second

    def __post_init__(self) -> None:
        from trajectories.errors import OptionError, SettingError

        if self.baud <= 0:
            raise SettingError(LabOptions, "baud", f"must be positive, got {self.baud}")
        if not 0 <= self.pendulum_zero < 4096:
            raise SettingError(
                LabOptions, "pendulum_zero", f"must be an encoder count 0..4095, got {self.pendulum_zero}"
            )
        if not (math.isfinite(self.mqtt_rate_hz) and 0 < self.mqtt_rate_hz <= 1000):
            raise SettingError(LabOptions, "mqtt_rate_hz", f"must be in (0, 1000] Hz, got {self.mqtt_rate_hz:g}")
        if self.mqtt is not None:
            try:
                parse_mqtt_url(self.mqtt, "")
            except OptionError as exc:
                raise SettingError(LabOptions, "mqtt", exc.message.lstrip(": ")) from None

    def validate(self, embedded: bool) -> None:
        """SettingError when the attachments do not go with the session (``embedded``: on the built-in simulator)."""
        from trajectories.errors import SettingError

        if self.pendulum == "sim" and not embedded:
            raise SettingError(
                LabOptions, "pendulum", "'sim' emulates the module in the built-in simulator; not with a robot"
            )


def snapshot(mon: Any, pendulum: PendulumReader | None) -> dict[str, Any]:
    """The state published per telemetry message (joints [rad], torques [Nm], IO values, pendulum)."""
    ci = mon.connectionInfo
    md = mon.monitorData
    d: dict[str, Any] = {
        "state": _STATES[ci.sessionState] if 0 <= ci.sessionState < len(_STATES) else str(ci.sessionState),
        "quality": int(ci.quality),
        "msr_q": list(md.measuredJointPosition.value),
        "ipo_q": list(mon.ipoData.jointPosition.value),
        "msr_tau": list(md.measuredTorque.value),
        "ext_tau": list(md.externalTorque.value),
        "tracking": mon.ipoData.trackingPerformance,
    }
    for io in md.readIORequest:
        d[io.name] = io.analogValue if io.HasField("analogValue") else int(io.digitalValue)
    r = pendulum.seen if pendulum is not None else None
    if r is not None:
        d["pend_theta"] = r.theta
        d["pend_omega"] = r.omega
    return d


class LabAttachments:
    """Started before the session, stopped after it; gives the session its extra log columns and its tap."""

    def __init__(self, options: LabOptions, pendulum_path: str | None, polled: bool = False) -> None:
        self.options = options
        self.pendulum = (PendulumReader(pendulum_path, options.baud, options.pendulum_zero, threaded=not polled)
                         if pendulum_path else None)  # fmt: skip
        self.publisher = (
            TelemetryPublisher(parse_mqtt_url(options.mqtt), options.mqtt_rate_hz) if options.mqtt else None
        )

    def start(self) -> "LabAttachments":
        if self.pendulum is not None:
            self.pendulum.start()
        if self.publisher is not None:
            self.publisher.start()
        return self

    def stop(self) -> None:
        if self.publisher is not None:
            self.publisher.stop()
        if self.pendulum is not None:
            self.pendulum.stop()

    @property
    def extra_names(self) -> tuple[str, ...]:
        return PENDULUM_COLUMNS if self.pendulum is not None else ()

    def extra(self, mon: Any) -> tuple[float, ...]:
        """pend_theta, pend_omega, pend_age for the log row (0, 0, −1 before the first reading: no missing values,
        so every CSV reader types the columns as numbers): the reading the cycle saw."""
        r = self.pendulum.seen if self.pendulum is not None else None
        if r is None:
            return (0.0, 0.0, -1.0)
        return (r.theta, r.omega, time.monotonic() - r.host_time)

    def pendulum_sway(self, state: Any) -> float | None:
        """The pendulum module's angle [rad] as a sway source (None before a reading or if it is 0.1 s old)."""
        r = self.pendulum.latest if self.pendulum is not None else None
        if r is None or time.monotonic() - r.host_time > 0.1:
            return None
        return r.theta

    def tap(self, t: float, mon: Any) -> None:
        pub = self.publisher
        if pub is not None and pub.due(t):
            pub.offer(t, snapshot(mon, self.pendulum))

    def summary(self) -> dict[str, Any]:
        d: dict[str, Any] = {}
        if self.pendulum is not None:
            d.update(
                pendulum_lines=self.pendulum.lines,
                pendulum_malformed=self.pendulum.malformed,
                pendulum_error=self.pendulum.error,
            )
        if self.publisher is not None:
            d.update(mqtt_published=self.publisher.published, mqtt_dropped=self.publisher.dropped)
        return d
