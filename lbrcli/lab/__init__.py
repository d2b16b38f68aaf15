"""Lab integration around an FRI session: the pendulum encoder module over serial, live telemetry over MQTT."""
